#include "stereo_fusion/session/OutputCadence.h"

namespace stereo_fusion {

OutputCadence OutputCadence::atRates(double mesh_hz, double markers_hz, double planning_hz,
                                     bool textured) {
  OutputCadence cadence(mesh_hz, markers_hz, textured);
  cadence.planning_period_s_ = planning_hz > 0.0 ? 1.0 / planning_hz : 0.0;
  return cadence;
}

OutputCadence OutputCadence::everyFrames(size_t mesh_every, size_t planning_every, bool textured) {
  OutputCadence cadence(0.0, 0.0, textured);
  cadence.mesh_every_ = mesh_every > 0 ? mesh_every : 1;
  cadence.planning_every_ = planning_every;
  return cadence;
}

MeshTiming OutputCadence::meshTiming(uint64_t frames_fused) const {
  if (mesh_waits_for_rate_) return MeshTiming::kDeferred;
  return frames_fused % mesh_every_ == 0 ? MeshTiming::kNow : MeshTiming::kDeferred;
}

bool OutputCadence::planningAfterFrame(uint64_t frames_fused) const {
  return planning_every_ > 0 && frames_fused % planning_every_ == 0;
}

}  // namespace stereo_fusion
