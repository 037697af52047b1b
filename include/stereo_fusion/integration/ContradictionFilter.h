#pragma once
#include <cstdint>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/integration/MeasurementImage.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// What the contradiction filter reads (from the parameter table: StageConfigs).
struct ContradictionConfig {
  double voxel_size_m = MapperConfig{}.voxel_size_m;
  double contradiction_min_weight = MapperConfig{}.contradiction_min_weight;
  double contradiction_sigmas = MapperConfig{}.contradiction_sigmas;
  double contradiction_max_share = MapperConfig{}.contradiction_max_share;
};

struct ContradictionStats {
  uint64_t tiles_with_surface = 0;  ///< 8×8-px tiles where a trusted confident surface lies
  uint64_t pixels_behind = 0;       ///< measurements beyond every confident surface of their tile
  uint64_t pixels_rejected = 0;     ///< of those, the isolated ones, made unusable (not fused)
};

/// Robust fusion against mismatches that repeat across neighbouring views: a measurement that
/// lands far behind a surface several views agree on is dropped before fusion, unless so many
/// measurements around it do the same that the world must have changed there.
///
/// 1. Confident surfaces: every voxel of the queued blocks (level 1, or level 2 where a block
///    has no level 1) with weight ≥ `contradiction_min_weight` and |sdf| below its edge is
///    splatted, over its footprint, into 8×8-px tiles: a tile keeps the farthest such surface
///    depth plus a voxel.
/// 2. Trust: a tile's surface counts only where the median of its 3×3 tiles' median measured
///    depths lies no farther than it plus the margin — a floater in front of what the frame
///    measures around it does not get to reject what lies behind it.
/// 3. Behind: a measurement beyond its tile's surface by more than the margin,
///    `contradiction_sigmas` σ_z at its depth (σ_d = disparity_noise_px), is behind every
///    confident surface there.
/// 4. Isolated: it is dropped, where its tile's surface is trusted, when at most
///    `contradiction_max_share` of the valid measurements of the 5×5 tiles around its own are
///    behind the confident surfaces of their tiles too (trusted or not). A moved object or a person
///    who left makes a whole region contradict the map: kept, so carving and the free-space decay
///    clear it as before.
///
/// Runs after the lookup (it splats the blocks the lookup queued) and before fusion; the lookup
/// may have queued a block only a dropped measurement reached: fusion then creates none.
/// Results do not depend on the number of threads.
class ContradictionFilter {
 public:
  static constexpr int kTilePx = 8;
  static constexpr int kShareWindowTiles = 2;  ///< on each side: 5×5 tiles

  /// `sigma_d_px`: the source's disparity noise for σ_z (the Mapper passes the larger of
  /// disparity_noise_px and the frame's own DisparityNoise).
  ContradictionStats apply(const StereoFrame& frame, const BlockOctree& octree,
                           const std::vector<VoxelBlock*>& blocks,
                           const ContradictionConfig& config, double sigma_d_px, ThreadPool* pool,
                           MeasurementImage* measurements);

 private:
  std::vector<float> tile_far_m_, tile_median_m_;
  std::vector<float> share_far_m_;  // step 1: the tiles of each share of the blocks
  std::vector<uint32_t> tile_valid_, tile_behind_;
  cv::Mat reject_;
};

}  // namespace stereo_fusion
