// What every meshing path reads for one owner: its neighbourhood (the owner and its 7
// +neighbours), where the submesh goes, the per-owner sample grid and the lattice points on
// lines. BlockMesher::mesh() fills it; the paths (MesherGeneralPath.h, MesherUniformPath.h,
// MesherMixedPath.h) keep what only they need in state of their own.
#pragma once
#include <cstddef>
#include <cstdint>

#include "MesherLattice.h"
#include "MesherScratch.h"
#include "stereo_fusion/map/VoxelBlock.h"
#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion::mesher {

struct MesherContext {
  const VoxelBlock* nb[8] = {};  // owner + (d & 1, (d >> 1) & 1, (d >> 2) & 1)
  const Voxel* voxels[8] = {};   // what the mesher samples of nb[d]: meshVoxels()
  int level[8] = {};
  int step[8] = {};
  bool uniform = true;         // every present neighbour has the owner's level
  float truncated_abs = 0.0f;  // 0.99 · Φ of the coarsest level present
  int64_t origin[3] = {};
  double unit = 0.0;
  SubMesh* out = nullptr;
  MeshScratch* scratch = nullptr;
  // Sample cache. Every point the mesher samples is a block face coordinate (16) or a voxel
  // centre of a present block on each axis; those coordinates get a dense grid index so
  // that each point is sampled once per owner instead of once per box using it.
  // (The arrays below have no initialisers: each is filled before it is read, and zeroing
  // ~2 KiB per owner showed up in the profile.)
  int8_t grid_index[3][kAxisCoords];  // −1: coordinate not in the grid
  int grid_coords[3][kAxisCoords];    // grid index → coordinate, ascending
  int grid_dim[3] = {};
  // Lattice points on lines along each axis, as bit masks over the coordinate u (bit u set:
  // a present block touching the line has a voxel centre at u). Indexed [axis][class of the
  // next axis' coordinate][class of the one after][u ≥ 16], class 0 below the block face
  // (only offset-0 blocks touch), 1 on it (both), 2 above (only offset-1 blocks). Built by
  // the box walks that meet hanging points (general and mixed), not by the uniform path.
  uint64_t line_points[3][3][3][2];

  /// Builds the grid's coordinates from the present blocks' levels (call after nb/step).
  void buildSampleGrid();
  /// Fills line_points from the present blocks' levels.
  void buildLinePoints();

  /// The lattice points strictly inside (u0, u1) on the line along `axis` through `fixed`
  /// (the segment lies on one side of the block face: u0 ≥ 16 or u1 ≤ 16).
  uint64_t hangingBits(int axis, const int fixed[3], int u0, int u1) const {
    auto cls = [](int q) { return q < kBlockUnits ? 0 : (q == kBlockUnits ? 1 : 2); };
    const uint64_t line = line_points[axis][cls(fixed[(axis + 1) % 3])][cls(fixed[(axis + 2) % 3])]
                                     [u0 >= kBlockUnits];
    const uint64_t inside = ((uint64_t{1} << u1) - 1) & ~((uint64_t{2} << u0) - 1);
    return line & inside;
  }

  /// True if the owner's core box starting at `lo` certainly yields nothing: a corner voxel is
  /// unobserved, or all corners have one sign (the exact signs of the samples there).
  bool coreBoxIsEmpty(const int lo[3]) const {
    const int level = this->level[0], shift = level + 1;
    const int i = (lo[0] - step[0]) >> shift, j = (lo[1] - step[0]) >> shift,
              k = (lo[2] - step[0]) >> shift;
    const float w = 1.0f / static_cast<float>(step[0]);
    bool any_negative = false, any_nonnegative = false;
    for (int c = 0; c < 8; ++c) {
      const Voxel& v = voxels[0][VoxelBlock::indexInLevel(levelSide(level), i + (c & 1),
                                                          j + ((c >> 1) & 1), k + (c >> 2))];
      if (!(v.weight > 0.0f)) return true;
      // samplePoint() yields (0 + w·sdf) / w; dividing by w > 0 (≤ 1) keeps the sign and
      // cannot underflow, and 0 + x ≥ 0 iff x ≥ 0: the sign of w·sdf is the sample's.
      (w * v.sdf_m >= 0.0f ? any_nonnegative : any_negative) = true;
    }
    return !(any_negative && any_nonnegative);
  }
};

}  // namespace stereo_fusion::mesher
