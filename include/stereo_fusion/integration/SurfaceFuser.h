#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/integration/FusionKernels.h"
#include "stereo_fusion/integration/DepthTiles.h"
#include "stereo_fusion/integration/MeasurementImage.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

struct FusionStats {
  uint64_t voxels_updated = 0;  ///< voxel updates over all levels
  uint64_t blocks_updated =
      0;  ///< queued blocks in which at least one voxel changed (created ones included)
  uint64_t blocks_created = 0;  ///< of the missing blocks, those the frame updated: new in the map
  uint64_t blocks_not_created =
      0;  ///< missing blocks the frame reached but did not update: never allocated
  uint64_t level_bytes_allocated =
      0;  ///< voxel bytes of the levels the frame allocated (created blocks' included)
};

/// Stage 2 of the pipeline (thesis §3.5): for every voxel of every queued block, at every
/// level, project the voxel centre into the disparity image (eq. 3.11–3.14), take the surface
/// depth seen by that pixel, and fuse the truncated signed distance (eq. 3.15) with its weight
/// (eq. 3.10) into the running average (eq. 3.8–3.9).
///
/// The level of a measurement follows the surface depth z (eq. 3.2): it updates its own level
/// and every coarser one, and the next finer one where the block holds it
/// (measurementUpdatesLevel(), see VoxelBlock), with Φ = TruncationBand::updateM(): truncation_vox
/// voxels of the measurement's level, but never less than 2 voxels of the level being updated.
/// Behind the surface, voxels farther than Φ are left untouched (unobserved); in front, the
/// distance is clamped to −Φ (observed free space).
///
/// Blocks are independent, so they run in parallel and the result does not depend on the
/// number of threads. The frame's disparities come converted to depths once per frame
/// (MeasurementImage, shared with the lookup); the voxel loop then runs eight voxels at a time on
/// CPUs with AVX2, with results bit-identical to the scalar loop (FusionKernels.h). The AVX2 loop
/// first puts whole groups of level-0 voxels to a conservative test against an 8×8-pixel summary of
/// the depths (DepthTiles) and skips those that provably get no update.
class SurfaceFuser {
 public:
  /// Which voxel loop fuse() runs. All give identical voxels; kAuto takes the fastest this CPU
  /// supports. The others let tests hold the paths against each other.
  enum class Kernel { kAuto, kScalar, kAvx2 };

  SurfaceFuser(const FusionConfig& config, ThreadPool* pool);

  /// Selects the voxel loop; kAvx2 on a CPU without AVX2 throws std::invalid_argument.
  void setKernel(Kernel kernel);

  /// Fuses `frame` into `blocks` (from BlockLookup); `updated` receives those that changed.
  /// `measurements` holds the frame's depths and colours (MeasurementImage::build(frame, config, …)
  /// with this fuser's configuration).
  FusionStats fuse(const StereoFrame& frame, const MeasurementImage& measurements,
                   const BlockOctree& octree, const std::vector<VoxelBlock*>& blocks,
                   std::vector<VoxelBlock*>* updated);

  /// fuse(), and the blocks at `missing` (keys the lookup found no block for): each is fused
  /// into a block of its own outside the map, which goes to `created` (in key order) only if
  /// the frame updated it, for the caller to insert (BlockOctree::insert()). So a block that
  /// the band reaches but no voxel of which is updated (behind the surface, outside the image,
  /// too coarse a measurement) is never allocated. `updated` holds the updated queued blocks only.
  FusionStats fuse(const StereoFrame& frame, const MeasurementImage& measurements,
                   const BlockOctree& octree, const std::vector<VoxelBlock*>& blocks,
                   const std::vector<BlockKey>& missing, std::vector<VoxelBlock*>* updated,
                   std::vector<std::unique_ptr<VoxelBlock>>* created);

 private:
  FusionConfig config_;
  ThreadPool* pool_;
  bool use_avx2_;
  DepthTiles tiles_;                         // reused across frames
  std::vector<uint64_t> per_block_updates_;  // reused across frames
  std::vector<size_t> per_block_new_bytes_;  // reused across frames
  std::vector<std::unique_ptr<VoxelBlock>>
      candidates_;  // one per missing key, reused across frames
};

}  // namespace stereo_fusion
