#include "stereo_fusion/integration/FramePipeline.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <utility>

#include "stereo_fusion/integration/DisparityCoherence.h"
#include "stereo_fusion/integration/DisparityNoise.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace {
/// `value` printed with `pattern`, e.g. "%.1f %%".
std::string format(const char* pattern, double value) {
  char text[32];
  std::snprintf(text, sizeof(text), pattern, value);
  return text;
}

/// A frame the gate passed but a later stage refuses is not fused, so the gate does not follow
/// it (no re-anchoring either).
bool refuse(FrameStageStats* stats, RejectReason reason, std::string error) {
  stats->reason = reason;
  stats->error = std::move(error);
  stats->reanchored = false;
  stats->note.clear();
  return false;
}
}  // namespace

FramePipeline::FramePipeline(const FramePipelineConfig& config, ThreadPool* pool)
    : config_(config),
      pool_(pool),
      gate_(config.gate),
      lookup_(config.lookup, pool),
      fuser_(config.fusion, pool),
      carver_(config.carve, pool) {}

bool FramePipeline::run(const StereoFrame& frame, BlockOctree* map, StageScope* stage,
                        FrameStageStats* stats, FrameEdit* edit) {
  edit->updated.clear();
  edit->created.clear();
  edit->level_bytes_allocated = 0;
  stats->error = validateFrame(frame, config_.block_size_m);
  if (!stats->error.empty()) {
    stats->reason = RejectReason::kInvalidFrame;
    return false;
  }
  std::string gate_message;
  stats->reason = gate_.check(frame, &gate_message, &stats->reanchored);
  if (stats->reason != RejectReason::kNone) stats->error = gate_message;
  if (stats->reanchored) stats->note = gate_message;
  if (stats->reason != RejectReason::kNone) return false;

  stage->enter(MapperStage::kLookup);
  const bool accepted = measureAndLookUp(frame, map, stats);
  if (accepted) {
    gate_.accepted(frame);
    stats->accepted = true;
    if (std::isfinite(stats->disparity_noise_px)) {
      recent_noise_px_.push_back(stats->disparity_noise_px);
      if (recent_noise_px_.size() > kNoiseFrames) recent_noise_px_.pop_front();
    }
    fuseAndCarve(frame, map, stage, stats, edit);
  }
  queue_.clear();  // the host may erase blocks before the next frame
  updated_.clear();
  carved_.clear();
  return accepted;
}

bool FramePipeline::measureAndLookUp(const StereoFrame& frame, BlockOctree* map,
                                     FrameStageStats* stats) {
  Timer lookup_timer;
  measurements_.build(frame, config_.measurement, pool_);
  stats->disparity_noise_px = measureDisparityNoise(frame.disparity_px, measurements_).sigma_px;
  if (config_.min_coherent_pixel_share > 0.0) {
    const DisparityCoherence coherence =
        measureDisparityCoherence(frame.disparity_px, measurements_, pool_);
    if (coherence.usable_pixels >= kCoherenceMinUsablePixels &&
        coherence.share() < config_.min_coherent_pixel_share)
      return refuse(stats, RejectReason::kIncoherentDisparity,
                    "only " + format("%.1f %%", 100.0 * coherence.share()) + " of its " +
                        std::to_string(coherence.usable_pixels) +
                        " usable disparities agree within " + format("%g", kCoherenceTolerancePx) +
                        " px with a neighbour, less than min_coherent_pixel_share (" +
                        format("%.1f %%", 100.0 * config_.min_coherent_pixel_share) +
                        "): a broken matcher or a wrong topic?");
  }
  // After the coherence check: rejection would leave a random frame's few coherent pixels.
  stats->rejected =
      outlier_rejection_.apply(frame.disparity_px, config_.outliers, &measurements_, pool_);
  stats->lookup = lookup_.run(frame, measurements_, map, &queue_, &missing_);
  stats->lookup_ms = lookup_timer.elapsedMs();
  if (stats->lookup.over_work_bound)
    return refuse(stats, RejectReason::kWorkBound,
                  "its truncation bands span " + std::to_string(stats->lookup.box_blocks) +
                      " blocks for the lookup to visit, more than max_lookup_blocks_per_frame (" +
                      std::to_string(config_.lookup.max_lookup_blocks_per_frame) +
                      "): an absurd calibration or depth range?");
  // The lookup only reads the map: a frame over its allocation budget leaves it untouched.
  if (config_.max_new_blocks_per_frame > 0 &&
      missing_.size() > static_cast<size_t>(config_.max_new_blocks_per_frame))
    return refuse(stats, RejectReason::kAllocationBudget,
                  "its truncation bands reach " + std::to_string(missing_.size()) +
                      " blocks not yet in the map, more than max_new_blocks_per_frame (" +
                      std::to_string(config_.max_new_blocks_per_frame) +
                      "): noise or a wrong calibration?");
  return true;
}

void FramePipeline::fuseAndCarve(const StereoFrame& frame, BlockOctree* map, StageScope* stage,
                                 FrameStageStats* stats, FrameEdit* edit) {
  if (config_.contradiction_filter) {
    Timer contradiction_timer;
    // Never finer than configured; noisier where the frame itself measures more.
    const double sigma_d_px = std::isfinite(stats->disparity_noise_px)
                                  ? std::max(config_.disparity_noise_px, stats->disparity_noise_px)
                                  : config_.disparity_noise_px;
    stats->contradiction = contradiction_.apply(frame, *map, queue_, config_.contradiction,
                                                sigma_d_px, pool_, &measurements_);
    stats->contradiction_ms = contradiction_timer.elapsedMs();
  }
  stage->enter(MapperStage::kFusion);
  Timer fusion_timer;
  stats->fusion =
      fuser_.fuse(frame, measurements_, *map, queue_, missing_, &updated_, &edit->created);
  edit->level_bytes_allocated = stats->fusion.level_bytes_allocated;
  for (const VoxelBlock* block : updated_) edit->updated.push_back(block->key);
  stats->fusion_ms = fusion_timer.elapsedMs();
  if (config_.free_space_carving) {
    // Before the created blocks join the map: they are the frame's own, fusion updated them.
    stage->enter(MapperStage::kCarving);
    Timer carve_timer;
    stats->carve = carver_.carve(frame, measurements_, *map, queue_, &carved_);
    std::vector<BlockKey> keys;
    for (const VoxelBlock* block : carved_) keys.push_back(block->key);
    std::vector<BlockKey> merged;
    std::set_union(edit->updated.begin(), edit->updated.end(), keys.begin(), keys.end(),
                   std::back_inserter(merged));
    edit->updated.swap(merged);
    stats->carve_ms = carve_timer.elapsedMs();
  }
}

double FramePipeline::measuredDisparityNoisePx() const {
  if (recent_noise_px_.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::vector<double> values(recent_noise_px_.begin(), recent_noise_px_.end());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace stereo_fusion
