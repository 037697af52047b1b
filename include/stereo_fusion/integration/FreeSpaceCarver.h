#pragma once
#include <cstdint>
#include <vector>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/integration/FusionKernels.h"
#include "stereo_fusion/integration/MeasurementImage.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// What FreeSpaceCarver (stage 2b) reads (from the parameter table: StageConfigs): fusion's bands
/// and weights (it builds the same FusionFrame; its decay per see-through frame is
/// fusion.free_space_decay) and the free-depth window.
struct CarveConfig {
  FusionConfig fusion;
  int free_space_window_px = MapperConfig{}.free_space_window_px;
};

struct CarveStats {
  uint64_t blocks_visited =
      0;                       ///< blocks of the map in the frame's view that fusion had not queued
  uint64_t blocks_carved = 0;  ///< of those, blocks in which some voxel was seen through
  uint64_t voxels_carved = 0;  ///< voxel updates, all levels
};

/// Free-space evidence (stage 2b, after fusion). A measured surface says the space between the
/// camera and it is empty. Fusion writes that only into the blocks the surface's band brings
/// (clamped to −Φ); an object that has gone (a person who walked on) or a stereo floater lies
/// in blocks no band reaches any more, and would stay forever. The carver visits the blocks of
/// the map in the frame's view that fusion did not queue, and updates every observed voxel, at
/// every level the block holds, that the frame sees through:
///
///   seen through  ⇔  d < −Φ, with d = eq. 3.15 against the *free depth* F of its pixel, and Φ
///                    the band fusion applies to that voxel's level for a measurement at depth F
///                    (TruncationBand::updateM()): the voxel lies in front of the surface by more
///                    than fusion's band;
///   update        :  W ← W·(1 − free_space_decay), then eq. 3.8–3.9 with d = −Φ and the weight
///                    fusion gives a voxel in front of its surface (measurementWeight()).
///
/// F is the smallest depth within free_space_window_px of the pixel, and no depth where any
/// pixel of that window has no measurement: a voxel near a depth edge, on a thin structure
/// the matcher lost in this frame, or seen at the edge of the valid area is left alone. The
/// decay makes recent evidence win: a surface seen for a hundred frames and then seen through
/// in some twenty is gone, where plain averaging would need a hundred.
///
/// Unobserved voxels stay unobserved and no block is allocated: unknown space stays unknown,
/// and memory does not grow. Blocks are independent (parallel, thread-count independent).
class FreeSpaceCarver {
 public:
  FreeSpaceCarver(const CarveConfig& config, ThreadPool* pool);

  /// Carves the frame into the blocks of `octree` in its view, except `queued` (fusion's blocks
  /// for this frame). `carved` receives the blocks that changed, sorted by key.
  CarveStats carve(const StereoFrame& frame, const MeasurementImage& measurements,
                   const BlockOctree& octree, const std::vector<VoxelBlock*>& queued,
                   std::vector<VoxelBlock*>* carved);

  /// The free depth F of pixel (u, v): the smallest depth within `window_px` of it (the window
  /// clipped to the image), 0 if a pixel of the window has no measurement (NaN).
  static float freeDepth(const float* depth_m, int width_px, int height_px, int window_px, int u,
                         int v);

 private:
  /// Largest depth per kTilePx² tile (0 where none): bounds the free depth under a footprint.
  void buildTileMaxima(const float* depth_m, int width_px, int height_px);

  CarveConfig config_;
  ThreadPool* pool_;
  std::vector<float> tile_max_depth_m_;  // largest depth per tile, reused across frames
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<uint32_t> queued_stamp_;  // by block row: the frame that queued it
  uint32_t stamp_ = 0;
  std::vector<VoxelBlock*> candidates_;  // reused across frames
  std::vector<uint8_t> keep_;            // per candidate: in view and seen through
  std::vector<uint64_t> block_updates_;  // per candidate
};

}  // namespace stereo_fusion
