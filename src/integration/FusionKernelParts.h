#pragma once
// What the scalar (FusionKernels.cpp) and the AVX2 (FusionKernelsAvx2.cpp) kernels share: the
// block's origin in the camera, the first level a visit must look at, and where a level is
// fused. Private to src/integration/.
#include <algorithm>
#include <cstdint>

#include <Eigen/Core>

#include "stereo_fusion/integration/FusionKernels.h"
#include "stereo_fusion/integration/FusionMath.h"

namespace stereo_fusion {
namespace fusion_kernels {

/// Block origin in camera coordinates: transformed in double (world coordinates may be large);
/// the small offsets to the voxel centres are then stepped in float.
inline Eigen::Vector3f blockOriginInCamera(const FusionFrame& f, const BlockOctree& octree,
                                           const BlockKey& key) {
  return (f.T_camera_world * octree.blockOrigin(key)).cast<float>();
}

/// Block-level depth test: a voxel is only updated by a surface at depth ≥ z_voxel − Φ
/// (eq. 3.15 with sdf ≤ Φ), and a level finer than the measurement's is skipped unless it is
/// the next finer one and the block holds it (measurementUpdatesLevel()). When even the
/// block's nearest corner is so far that every possible measurement is of level m or coarser,
/// the levels finer than m cannot change, except m − 1 where the block holds it: the kernels
/// start at the returned level.
inline int firstLevelToVisit(const FusionFrame& f, const Eigen::Vector3f& origin_c,
                             const VoxelBlock& block) {
  const float block_m = f.voxel_m * kFinestSide;
  float nearest_z = origin_c.z();
  for (int c = 1; c < 8; ++c)
    nearest_z = std::min(nearest_z, origin_c.z() + block_m * ((c & 1 ? f.R_cw(2, 0) : 0.0f) +
                                                              (c & 2 ? f.R_cw(2, 1) : 0.0f) +
                                                              (c & 4 ? f.R_cw(2, 2) : 0.0f)));
  // Margin: the voxel loop computes depths with other float roundings.
  const double nearest_surface_m = static_cast<double>(nearest_z) - f.max_truncation_m - 1e-3;
  const int finest_measurement_level = levelForDepth(nearest_surface_m, f.thresholds);
  const int finer = finest_measurement_level - 1;
  if (finer >= 0 && measurementUpdatesLevel(finest_measurement_level, finer, block.hasLevel(finer),
                                            f.update_allocated_finer))
    return finer;
  return finest_measurement_level;
}

/// Where a kernel fuses one level of `block`: the level's storage when allocated, else this
/// thread's scratch level, which is all unobserved (a visit that updates no voxel writes none:
/// the AVX2 kernel stores a group of eight only when a lane of it is updated). commit() adopts
/// the scratch into the block only if the level was updated and zeroes it again, so a visit
/// that updates nothing allocates nothing.
class LevelTarget {
 public:
  LevelTarget(VoxelBlock* block, int level)
      : block_(block), level_(level), voxels_(block->levelIfAllocated(level)) {
    if (voxels_ == nullptr) {
      static thread_local Voxel scratch[levelVoxelCount(0)];
      voxels_ = scratch;
      scratch_ = true;
    }
  }
  Voxel* voxels() const { return voxels_; }
  uint64_t commit(uint64_t updates) {
    if (scratch_ && updates > 0) {
      block_->adoptLevel(level_, voxels_);
      std::fill(voxels_, voxels_ + levelVoxelCount(level_), Voxel{});
    }
    return updates;
  }

 private:
  VoxelBlock* block_;
  int level_;
  Voxel* voxels_;
  bool scratch_ = false;
};

}  // namespace fusion_kernels
}  // namespace stereo_fusion
