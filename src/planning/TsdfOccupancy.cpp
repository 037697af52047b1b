#include "stereo_fusion/planning/TsdfOccupancy.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace stereo_fusion {

namespace {

/// Trilinear interpolation of `level`'s evidence voxels at a point given in finest-voxel units
/// of the block, renormalised over the corners that are evidence; NaN if none is. With all 8
/// corners evidence, divided by the gradient's length where that exceeds 1 (projective →
/// Euclidean, see TsdfCellState::centre_sdf_m).
float interpolateEvidence(const Voxel* voxels, int level, const TsdfCellParams& params,
                          const Eigen::Vector3f& point_vox) {
  const int side = levelSide(level), scale = levelScale(level);
  int base[3];
  float t[3];
  for (int a = 0; a < 3; ++a) {
    // Voxel x of the level has its centre at (x + 0.5)·scale finest voxels.
    const float q = point_vox[a] / static_cast<float>(scale) - 0.5f;
    base[a] = std::clamp(static_cast<int>(std::floor(q)), 0, std::max(side - 2, 0));
    t[a] = side < 2 ? 0.0f : std::clamp(q - static_cast<float>(base[a]), 0.0f, 1.0f);
  }
  float sum = 0.0f, total = 0.0f;
  Eigen::Vector3f gradient = Eigen::Vector3f::Zero();  // of the trilinear field, per level voxel
  int corners = 0;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const int x = std::min(base[0] + i, side - 1), y = std::min(base[1] + j, side - 1),
                  z = std::min(base[2] + k, side - 1);
        const Voxel& v = voxels[VoxelBlock::indexInLevel(side, x, y, z)];
        if (!(v.weight >= params.min_weight)) continue;
        const float wx = i ? t[0] : 1.0f - t[0], wy = j ? t[1] : 1.0f - t[1],
                    wz = k ? t[2] : 1.0f - t[2];
        sum += wx * wy * wz * v.sdf_m;
        total += wx * wy * wz;
        gradient += Eigen::Vector3f((i ? 1.0f : -1.0f) * wy * wz, (j ? 1.0f : -1.0f) * wx * wz,
                                    (k ? 1.0f : -1.0f) * wx * wy) *
                    v.sdf_m;
        ++corners;
      }
  if (!(total > 0.0f)) return std::numeric_limits<float>::quiet_NaN();
  float sdf = sum / total;
  if (corners == 8 && side >= 2) {
    const float slope = gradient.norm() / (static_cast<float>(scale) * params.voxel_m);
    if (slope > 1.0f) sdf /= slope;
  }
  return sdf;
}

}  // namespace

void tsdfCellStates(const BlockKey& tsdf_key, const VoxelBlock* block, const TsdfCellParams& params,
                    std::vector<TsdfCellState>* out) {
  const int voxels_per_cell = params.voxels_per_cell;
  const float min_weight = params.min_weight;
  const int cells = 8 / voxels_per_cell;  // per axis in one TSDF block
  const size_t first = out->size();
  for (int k = 0; k < cells; ++k)
    for (int j = 0; j < cells; ++j)
      for (int i = 0; i < cells; ++i)
        out->push_back(
            {CellIndex{tsdf_key.x * cells + i, tsdf_key.y * cells + j, tsdf_key.z * cells + k}});
  if (block == nullptr) return;
  // Per cell and level: bit 0 evidence, bit 1 evidence of a surface (sdf ≥ 0).
  std::array<std::array<uint8_t, 512>, kNumLevels> flags{};
  for (int level = 0; level < kNumLevels; ++level) {
    if (!block->hasLevel(level)) continue;
    const Voxel* voxels = block->level(level);
    const int side = levelSide(level), scale = levelScale(level);
    for (int z = 0; z < side; ++z)
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
          const Voxel& v = voxels[VoxelBlock::indexInLevel(side, x, y, z)];
          if (!(v.weight > 0.0f) || !(v.weight >= min_weight)) continue;
          const uint8_t bits = static_cast<uint8_t>(1u | (v.sdf_m >= 0.0f ? 2u : 0u));
          // The voxel spans finest voxels [x·scale, (x+1)·scale) along each axis.
          auto range = [&](int c, int* lo, int* hi) {
            *lo = c * scale / voxels_per_cell;
            *hi = ((c + 1) * scale - 1) / voxels_per_cell;
          };
          int x0, x1, y0, y1, z0, z1;
          range(x, &x0, &x1);
          range(y, &y0, &y1);
          range(z, &z0, &z1);
          for (int cz = z0; cz <= z1; ++cz)
            for (int cy = y0; cy <= y1; ++cy)
              for (int cx = x0; cx <= x1; ++cx)
                flags[level][cx + cells * (cy + cells * cz)] |= bits;
        }
  }
  const float half = 0.5f * static_cast<float>(voxels_per_cell);
  for (int c = 0; c < cells * cells * cells; ++c)
    for (int level = 0; level < kNumLevels; ++level)
      if (flags[level][c] & 1u) {
        TsdfCellState& s = (*out)[first + c];
        s.observed = true;
        s.occupied = (flags[level][c] & 2u) != 0;
        const Eigen::Vector3f centre_vox(
            static_cast<float>(c % cells * voxels_per_cell) + half,
            static_cast<float>(c / cells % cells * voxels_per_cell) + half,
            static_cast<float>(c / (cells * cells) * voxels_per_cell) + half);
        s.centre_sdf_m = interpolateEvidence(block->level(level), level, params, centre_vox);
        break;
      }
}

}  // namespace stereo_fusion
