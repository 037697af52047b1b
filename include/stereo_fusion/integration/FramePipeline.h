#pragma once
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "stereo_fusion/MapperStage.h"
#include "stereo_fusion/integration/BlockLookup.h"
#include "stereo_fusion/integration/ContradictionFilter.h"
#include "stereo_fusion/integration/FrameGate.h"
#include "stereo_fusion/integration/FreeSpaceCarver.h"
#include "stereo_fusion/integration/MeasurementImage.h"
#include "stereo_fusion/integration/OutlierRejection.h"
#include "stereo_fusion/integration/RejectReason.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/integration/SurfaceFuser.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// What the frame pipeline's stages did with one frame (the map host adds what it and the
/// layers did: IntegrationResult).
struct FrameStageStats {
  bool accepted = false;  ///< false: the frame was rejected and the map is unchanged
  RejectReason reason = RejectReason::kNone;  ///< why it was rejected, for counters
  std::string error;                          ///< why it was rejected, one sentence
  /// Accepted only because the frames rejected before it agreed with it (FrameGate: a
  /// relocalisation or a clock reset); `note` says why.
  bool reanchored = false;
  std::string note;
  /// The frame's depths and colours, its disparity noise (DisparityNoise), coherence, outlier
  /// rejection and the lookup.
  double lookup_ms = 0.0;
  double fusion_ms = 0.0;  ///< the surface update and the insertion of the frame's new blocks
  double carve_ms = 0.0;   ///< free-space carving (FreeSpaceCarver), included in nothing else
  double contradiction_ms = 0.0;  ///< ContradictionFilter, included in nothing else
  /// Usable pixels the outlier rejection dropped (counted, not fused).
  OutlierRejectionStats rejected;
  /// Usable pixels dropped as isolated contradictions of confident surfaces (counted, not fused).
  ContradictionStats contradiction;
  /// The frame's disparity noise σ_d measured from its own disparities (DisparityNoise), px;
  /// NaN when it had too few usable samples or the frame was rejected before.
  double disparity_noise_px = std::numeric_limits<double>::quiet_NaN();
  LookupStats lookup;
  FusionStats fusion;
  CarveStats carve;
};

/// What the frame pipeline reads (from the parameter table: StageConfigs): each stage's own
/// config, and the pipeline's refusals.
struct FramePipelineConfig {
  double block_size_m = MapperConfig{}.blockSizeM();  ///< validateFrame()'s block grid
  FrameGateLimits gate;
  MeasurementConfig measurement;
  OutlierConfig outliers;
  LookupConfig lookup;
  FusionConfig fusion;
  CarveConfig carve;
  ContradictionConfig contradiction;
  bool contradiction_filter = MapperConfig{}.contradiction_filter;
  bool free_space_carving = MapperConfig{}.free_space_carving;
  /// σ_d the contradiction filter assumes at least (it uses the frame's own when larger).
  double disparity_noise_px = MapperConfig{}.disparity_noise_px;
  double min_coherent_pixel_share = MapperConfig{}.min_coherent_pixel_share;
  int max_new_blocks_per_frame = MapperConfig{}.max_new_blocks_per_frame;
};

/// The map edit a fused frame leaves for the map host to apply.
struct FrameEdit {
  /// Blocks of the map the frame changed in place (fusion, carving), sorted by key.
  std::vector<BlockKey> updated;
  /// Blocks the frame created, not yet in the map, in key order: the host inserts them.
  std::vector<std::unique_ptr<VoxelBlock>> created;
  /// Bytes of voxel levels the frame allocated (in `updated` blocks and `created` ones).
  size_t level_bytes_allocated = 0;
};

/// The stages a frame goes through before its edit reaches the map: validation and the
/// FrameGate, the measurement image and its disparity noise, the coherence check, outlier
/// rejection, the block lookup, the contradiction filter, fusion and free-space carving. Owns
/// their scratch; reads the map, and updates the blocks already in it in place (nothing else
/// touches them meanwhile); new blocks are left in the edit.
class FramePipeline {
 public:
  FramePipeline(const FramePipelineConfig& config, ThreadPool* pool);

  /// Runs `frame` through the stages against `map`. False, the map untouched, when a stage
  /// refuses it (`stats` says why); true with the frame's edit in `edit` (cleared first).
  bool run(const StereoFrame& frame, BlockOctree* map, StageScope* stage, FrameStageStats* stats,
           FrameEdit* edit);
  /// The last frame's depths and colours (what a layer's per-frame hook reads).
  const MeasurementImage& measurements() const { return measurements_; }
  /// Where the last fused frame's camera was (nullopt before the first, after forget()).
  const std::optional<Eigen::Vector3d>& lastFusedPosition() const {
    return gate_.lastFusedPosition();
  }
  /// The median of the last kNoiseFrames frames' measured disparity noise (px), NaN before any.
  double measuredDisparityNoisePx() const;
  static constexpr size_t kNoiseFrames = 31;
  /// A new map (reset, load): the gate follows no frame. The noise history stays (a property
  /// of the camera, not of the map).
  void forget() { gate_.reset(); }

 private:
  /// The frame's measurements, noise, coherence check, outlier rejection and lookup; false
  /// with the reason in `stats` when one refuses it.
  bool measureAndLookUp(const StereoFrame& frame, BlockOctree* map, FrameStageStats* stats);
  /// Contradiction filter, fusion and carving of an accepted frame.
  void fuseAndCarve(const StereoFrame& frame, BlockOctree* map, StageScope* stage,
                    FrameStageStats* stats, FrameEdit* edit);

  const FramePipelineConfig config_;
  ThreadPool* pool_;
  FrameGate gate_;
  MeasurementImage measurements_;
  OutlierRejection outlier_rejection_;
  ContradictionFilter contradiction_;
  BlockLookup lookup_;
  SurfaceFuser fuser_;
  FreeSpaceCarver carver_;
  std::deque<double> recent_noise_px_;  // the last kNoiseFrames frames' measured σ_d
  // Reused across frames; block pointers are dropped at the end of run() (the host may erase).
  std::vector<VoxelBlock*> queue_, updated_, carved_;
  std::vector<BlockKey> missing_;
};

}  // namespace stereo_fusion
