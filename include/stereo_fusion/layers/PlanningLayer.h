#pragma once
#include <functional>
#include <optional>

#include "stereo_fusion/layers/MapLayer.h"
#include "stereo_fusion/planning/PlanningMap.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// What the planning layer reads (from the parameter table: StageConfigs).
struct PlanningLayerConfig {
  PlanningConfig planning;
  /// max_distance_from_camera_m: the seen-free space farther from the camera is dropped with
  /// the TSDF blocks the memory bound evicts. 0 = unlimited.
  double max_distance_from_camera_m = 0.0;
};

/// What one planning update did.
struct PlanningPass {
  PlanningUpdateStats stats;
  double esdf_ms = 0.0;  ///< re-reading the changed TSDF blocks' cells and updating the ESDF
};

/// The planning layer (PlanningMap: seen-free space, occupancy, the ESDF) as a layer of the
/// map: every frame's free space is recorded as it is fused; the rest follows the TSDF's
/// changes at the caller's cadence, or in two halves (begin() with the map, finish() without).
class PlanningLayer final : public MapLayer {
 public:
  PlanningLayer(const PlanningLayerConfig& config, ThreadPool* pool)
      : config_(config), map_(config.planning, pool) {}

  const char* name() const override { return "planning"; }
  /// Records the space the frame saw empty (frameFreeSpace()).
  void onFrame(const LayerFrame& frame) override;
  void update(const BlockOctree& map, const BlockChangeLog::Changes& changes) override {
    finish(begin(map, changes));
  }
  /// update() in two halves: begin() reads the changed TSDF blocks' cells from `map`; finish()
  /// touches only this layer and may run on another thread while frames are fused.
  PlanningMap::PendingUpdate begin(const BlockOctree& map, const BlockChangeLog::Changes& changes) {
    return map_.beginUpdate(map, changes.updated, changes.erased);
  }
  PlanningPass finish(PlanningMap::PendingUpdate pending,
                      const std::function<void(const PlanningPass&)>& before_end = {});
  void rebuild(const BlockOctree& map) override { map_.rebuild(map); }
  PlanningPass rebuildTimed(const BlockOctree& map);
  void clearRegion(const MapRegion& region) override { map_.clearRegion(region); }
  void reset() override { map_.clear(); }
  /// The seen-free cells: the only part of the layer not derived from the TSDF.
  void encode(MapFileInfo* info) const override;
  /// The file's seen-free cells if they are of this layer's cell size (else its free space is
  /// unknown, as with an older file), then the rest from the TSDF.
  void adopt(const BlockOctree& map, const MapFileInfo& info) override;

  const PlanningMap& map() const { return map_; }
  /// What recording the last frame's free space did.
  const FreeSpaceStats& frameFreeSpace() const { return frame_free_space_; }

 private:
  const PlanningLayerConfig config_;
  PlanningMap map_;
  FreeSpaceStats frame_free_space_;
};

}  // namespace stereo_fusion
