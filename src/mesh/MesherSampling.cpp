#include "MesherSampling.h"

#include <algorithm>

#include "stereo_fusion/mesh/BlockMesher.h"

namespace stereo_fusion::mesher {
namespace {

/// Trilinear interpolation of one block's voxels of `level` (`voxels`: levelVoxelCount(level)
/// of them, VoxelBlock::index() order) at block-local lattice coordinates (0..16, in half
/// finest voxels), clamped to the block's voxel centres. False if a sample that contributes is
/// unobserved.
bool blockField(const Voxel* voxels, int level, const int local[3], float* sdf, float rgb[3]) {
  const int step = 1 << level;
  const int side = kFinestSide >> level;
  // Centres are `den` = 2·step apart: shifts and masks instead of integer division (the
  // operands below are non-negative where divided, so the results are the same).
  const int den = 2 * step;
  const int shift = level + 1;
  const int mask = den - 1;
  // Most points are voxel centres: read the voxel (what the interpolation below yields).
  if (((local[0] - step) & mask) == 0 && ((local[1] - step) & mask) == 0 &&
      ((local[2] - step) & mask) == 0 && local[0] > 0 && local[1] > 0 && local[2] > 0 &&
      local[0] < kBlockUnits && local[1] < kBlockUnits && local[2] < kBlockUnits) {
    const Voxel& v = voxels[VoxelBlock::indexInLevel(
        side, (local[0] - step) >> shift, (local[1] - step) >> shift, (local[2] - step) >> shift)];
    if (!(v.weight > 0.0f)) return false;
    *sdf = v.sdf_m;
    rgb[0] = v.r;
    rgb[1] = v.g;
    rgb[2] = v.b;
    return true;
  }
  int i0[3];
  float frac[3];
  for (int a = 0; a < 3; ++a) {
    const int num = std::clamp(local[a] - step, 0, (side - 1) * den);
    i0[a] = num >> shift;
    int rem = num & mask;
    if (i0[a] == side - 1) {  // on the last centre: use the last cell with fraction 1
      i0[a] = side - 2;
      rem = den;
    }
    frac[a] = static_cast<float>(rem) / static_cast<float>(den);
  }
  // On centre planes in every axis (block faces clamp to the outer centres): one voxel with
  // weight 1. The sums start at +0 as in the loop below, so −0 reads as +0 there too.
  if ((frac[0] == 0.0f || frac[0] == 1.0f) && (frac[1] == 0.0f || frac[1] == 1.0f) &&
      (frac[2] == 0.0f || frac[2] == 1.0f)) {
    const Voxel& v = voxels[VoxelBlock::indexInLevel(
        side, i0[0] + (frac[0] == 1.0f), i0[1] + (frac[1] == 1.0f), i0[2] + (frac[2] == 1.0f))];
    if (!(v.weight > 0.0f)) return false;
    *sdf = 0.0f + v.sdf_m;
    rgb[0] = 0.0f + v.r;
    rgb[1] = 0.0f + v.g;
    rgb[2] = 0.0f + v.b;
    return true;
  }
  return trilinearVoxels(voxels, side, i0, frac, sdf, rgb);
}

}  // namespace

bool samplePoint(const MesherContext& ctx, int qx, int qy, int qz, PointSample* out) {
  const int q[3] = {qx, qy, qz};
  int first[3], last[3];
  for (int a = 0; a < 3; ++a) incidentRange(q[a], &first[a], &last[a]);
  float weight_sum = 0.0f, acc = 0.0f, acc_rgb[3] = {0, 0, 0};
  // Fixed order (z, y, x outer to inner): every owner sums a shared point identically.
  for (int dz = first[2]; dz <= last[2]; ++dz)
    for (int dy = first[1]; dy <= last[1]; ++dy)
      for (int dx = first[0]; dx <= last[0]; ++dx) {
        const int d = dx + 2 * dy + 4 * dz;
        if (ctx.nb[d] == nullptr) return false;
        const int local[3] = {qx - kBlockUnits * dx, qy - kBlockUnits * dy, qz - kBlockUnits * dz};
        float sdf, rgb[3];
        if (!blockField(ctx.voxels[d], ctx.level[d], local, &sdf, rgb)) return false;
        const float w = 1.0f / static_cast<float>(ctx.step[d]);  // finer block, nearer centre
        weight_sum += w;
        acc += w * sdf;
        for (int k = 0; k < 3; ++k) acc_rgb[k] += w * rgb[k];
      }
  out->sdf = acc / weight_sum;
  for (int k = 0; k < 3; ++k) out->rgb[k] = acc_rgb[k] / weight_sum;
  return true;
}

}  // namespace stereo_fusion::mesher
