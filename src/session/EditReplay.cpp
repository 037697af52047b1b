#include "stereo_fusion/session/EditReplay.h"

namespace stereo_fusion {

bool Edit::loadFrame(StereoFrame* out, std::string* error) const {
  if (!reload) {
    *out = frame;
    return true;
  }
  if (!reload(out, error)) return false;
  // Fused at the pose the live map used, whatever the source says now.
  out->timestamp_s = frame.timestamp_s;
  out->T_world_camera = frame.T_world_camera;
  return true;
}

EditReplay::FrameApplied EditReplay::frame(Mapper* mapper, const StereoFrame& posed,
                                           const Edit& edit, MeshTiming timing) {
  FrameApplied applied;
  applied.result = mapper->integrate(posed, timing);
  if (!applied.result.accepted) return applied;  // the map is unchanged: nothing to clear again
  for (const Edit& clear : pending_) {
    if (!predates(edit, clear)) continue;
    applied.recleared =
        mapper->clearRegion(clear.region, timing).voxels_cleared > 0 || applied.recleared;
  }
  while (!pending_.empty() && !predates(edit, pending_.front())) pending_.pop_front();
  return applied;
}

ClearResult EditReplay::clear(Mapper* mapper, const Edit& clear, MeshTiming timing) {
  ClearResult result = mapper->clearRegion(clear.region, timing);
  if (result.accepted) pending_.push_back(clear);
  return result;
}

const char* refusionStatusName(RefusionStatus status) {
  switch (status) {
    case RefusionStatus::kDone: return "done";
    case RefusionStatus::kCancelled: return "cancelled";
    case RefusionStatus::kUnreadableBase: return "unreadable base";
    case RefusionStatus::kUnreadableFrame: return "unreadable frame";
  }
  return "unknown";
}

RefusionStatus replayEdits(const std::vector<Edit>& edits, const PoseCorrection& correction,
                           Mapper* mapper, EditReplay* replay,
                           const std::function<bool()>& cancelled, RefusionProgress* progress,
                           std::string* error) {
  for (const Edit& edit : edits) {
    if (!edit.isFrame()) {
      replay->clear(mapper, edit, MeshTiming::kDeferred);
      continue;
    }
    if (cancelled && cancelled()) return RefusionStatus::kCancelled;
    StereoFrame original;
    if (!edit.loadFrame(&original, error)) return RefusionStatus::kUnreadableFrame;
    ++progress->frames;
    if (!replay->frame(mapper, correction.corrected(original), edit, MeshTiming::kDeferred)
             .result.accepted)
      ++progress->rejected;
  }
  return RefusionStatus::kDone;
}

}  // namespace stereo_fusion
