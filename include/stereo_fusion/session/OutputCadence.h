#pragma once
// When the outputs derived from the map are brought up to date around the frames — meshing,
// the planning layer's update, the markers — the one rule the node's adapters (FrameInput,
// MeshPublisher, PlanningPublisher) and the offline fuser follow.
#include <cstddef>
#include <cstdint>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/util/RateSchedule.h"

namespace stereo_fusion {

class OutputCadence {
 public:
  /// The node: meshing (and ~mesh_update) at most at `mesh_hz` (0: after every frame), markers
  /// at most at `markers_hz`, the planning layer on a timer at `planning_hz`.
  static OutputCadence atRates(double mesh_hz, double markers_hz, double planning_hz,
                               bool textured);
  /// The offline fuser: meshing after every `mesh_every`-th fused frame, the planning layer's
  /// update after every `planning_every`-th (and both after the last: the caller's).
  static OutputCadence everyFrames(size_t mesh_every, size_t planning_every, bool textured);

  /// How the `frames_fused`-th fused frame (counted from 1, this one included) is meshed.
  /// texture = patches: meshing waits for no rate, as a patch is cut from the frame of the
  /// meshing pass that changed its submesh; a period in frames (the fuser's --mesh-every) is
  /// the user's explicit choice and kept.
  MeshTiming meshTiming(uint64_t frames_fused) const;
  /// True if the planning layer is brought up to date right after that frame (the offline
  /// fuser; the node updates it on its own timer, planningPeriodS()).
  bool planningAfterFrame(uint64_t frames_fused) const;
  double planningPeriodS() const { return planning_period_s_; }

  /// The rate-limited meshing pass and its ~mesh_update: due at `now_s`? `frames_waiting`: a
  /// frame waits to be fused that the pass would then carry, so it may wait up to a period.
  bool meshDue(double now_s, bool frames_waiting) const { return mesh_.due(now_s, frames_waiting); }
  /// A due pass ran at `now_s` (one out of turn, forced, leaves the schedule as it was).
  void meshSent(double now_s) { mesh_.sent(now_s); }
  bool markersDue(double now_s) const { return markers_.due(now_s); }
  void markersSent(double now_s) { markers_.sent(now_s); }

 private:
  OutputCadence(double mesh_hz, double markers_hz, bool textured)
      : mesh_(mesh_hz), markers_(markers_hz), mesh_waits_for_rate_(mesh_hz > 0.0 && !textured) {}

  RateSchedule mesh_, markers_;
  bool mesh_waits_for_rate_;   // kDeferred always: the publisher meshes at its rate
  size_t mesh_every_ = 1;      // frames
  size_t planning_every_ = 0;  // frames; 0: not after frames
  double planning_period_s_ = 0.0;
};

}  // namespace stereo_fusion
