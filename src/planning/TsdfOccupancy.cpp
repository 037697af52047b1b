#include "stereo_fusion/planning/TsdfOccupancy.h"

#include <array>

namespace stereo_fusion {

void tsdfCellStates(const BlockKey& tsdf_key, const VoxelBlock* block, int voxels_per_cell,
                    std::vector<TsdfCellState>* out) {
  const int cells = 8 / voxels_per_cell;  // per axis in one TSDF block
  const size_t first = out->size();
  for (int k = 0; k < cells; ++k)
    for (int j = 0; j < cells; ++j)
      for (int i = 0; i < cells; ++i)
        out->push_back(
            {CellIndex{tsdf_key.x * cells + i, tsdf_key.y * cells + j, tsdf_key.z * cells + k}});
  if (block == nullptr) return;
  // Per cell and level: bit 0 observed, bit 1 occupied.
  std::array<std::array<uint8_t, 512>, kNumLevels> flags{};
  for (int level = 0; level < kNumLevels; ++level) {
    if (!block->hasLevel(level)) continue;
    const Voxel* voxels = block->level(level);
    const int side = levelSide(level), scale = levelScale(level);
    for (int z = 0; z < side; ++z)
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
          const Voxel& v = voxels[VoxelBlock::indexInLevel(side, x, y, z)];
          if (!(v.weight > 0.0f)) continue;
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
  for (int c = 0; c < cells * cells * cells; ++c)
    for (int level = 0; level < kNumLevels; ++level)
      if (flags[level][c] & 1u) {
        (*out)[first + c].observed = true;
        (*out)[first + c].occupied = (flags[level][c] & 2u) != 0;
        break;
      }
}

}  // namespace stereo_fusion
