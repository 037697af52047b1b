// The general sampler: a lattice point's value as the 1/s-weighted mean of the touching
// blocks' trilinear fields (BlockMesher.h, "Geometry"), and the per-owner cache in front of it.
#pragma once
#include <cstddef>
#include <cstdint>

#include "MesherContext.h"

namespace stereo_fusion::mesher {

/// The fused value at lattice point (qx, qy, qz): false if a touching block is absent or a
/// voxel it weighs there is unobserved. Every owner sums a shared point identically.
bool samplePoint(const MesherContext& ctx, int qx, int qy, int qz, PointSample* out);

/// samplePoint() through the owner's sample grid: each grid point is sampled once per owner.
inline bool cachedSample(MesherContext& ctx, const int q[3], PointSample* out) {
  const int gx = ctx.grid_index[0][q[0]], gy = ctx.grid_index[1][q[1]],
            gz = ctx.grid_index[2][q[2]];
  if ((gx | gy | gz) < 0) return samplePoint(ctx, q[0], q[1], q[2], out);  // not expected
  const size_t g = (static_cast<size_t>(gz) * ctx.grid_dim[1] + gy) * ctx.grid_dim[0] + gx;
  MeshScratch& m = *ctx.scratch;
  uint8_t& state = m.sample_state[g];
  if (state == kUnknown) {
    state = samplePoint(ctx, q[0], q[1], q[2], &m.samples[g]) ? kObserved : kUnobserved;
  }
  if (state != kObserved) return false;
  *out = m.samples[g];
  return true;
}

}  // namespace stereo_fusion::mesher
