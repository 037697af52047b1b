#include "stereo_fusion/layers/PlanningLayer.h"

#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

void PlanningLayer::onFrame(const LayerFrame& frame) {
  frame_free_space_ = map_.recordFreeSpace(frame.frame, frame.measurements);
  if (config_.max_distance_from_camera_m > 0.0)
    map_.dropFartherThan(frame.frame.T_world_camera.translation(),
                         config_.max_distance_from_camera_m);
}

PlanningPass PlanningLayer::finish(PlanningMap::PendingUpdate pending,
                                   const std::function<void(const PlanningPass&)>& before_end) {
  Timer timer;
  PlanningPass pass;
  // Timed up to the update's end proper: adding the frames' kept free space is theirs.
  map_.finishUpdate(std::move(pending), [&](const PlanningUpdateStats& stats) {
    pass.stats = stats;
    pass.esdf_ms = stats.read_ms + timer.elapsedMs();
    if (before_end) before_end(pass);
  });
  return pass;
}

PlanningPass PlanningLayer::rebuildTimed(const BlockOctree& map) {
  Timer timer;
  PlanningPass pass;
  pass.stats = map_.rebuild(map);
  pass.esdf_ms = timer.elapsedMs();
  return pass;
}

void PlanningLayer::encode(MapFileInfo* info) const {
  info->free_space.cell_m = map_.grid().cell_m;
  info->free_space.blocks = map_.seenFree();
}

void PlanningLayer::adopt(const BlockOctree& map, const MapFileInfo& info) {
  map_.clear();
  if (info.free_space.cell_m == map_.grid().cell_m) map_.addSeenFree(info.free_space.blocks);
  map_.rebuild(map);
}

}  // namespace stereo_fusion
