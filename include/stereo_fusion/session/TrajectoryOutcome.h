#pragma once
#include <cstddef>
#include <cstdint>

#include "stereo_fusion/util/EnumCounters.h"

namespace stereo_fusion {

/// What became of a corrected trajectory (a SLAM's loop closure): the one list, counted on
/// /diagnostics and named in logs. A new outcome is one value and one row in TrajectoryOutcome.cpp.
enum class TrajectoryOutcome : uint8_t {
  kApplied,  ///< the kept frames were fused again at the corrected poses, the maps swapped
  kAppliedWithoutRefusion,  ///< it moves no kept frame visibly: taken for the frames still to leave
                            ///< the window
  kSuperseded,  ///< a newer trajectory came before it was applied (waiting or being fused again)
  kDroppedByReset,       ///< a reset or load_map replaced the map it was for
  kRejectedWrongFrame,   ///< its header's frame is not world_frame
  kRejectedNothingKept,  ///< loop_closure_max_frames is 0
  kRejectedNoFrameYet,   ///< no frame has been fused yet
  kRejectedNoTransform,  ///< no transform from trajectory_frame to the camera
  kRejectedBadPose,      ///< a pose is not finite or its quaternion is no rotation
  kRejectedEmpty,        ///< it holds no pose
  kRejectedNoMatch,      ///< none of its stamps lies near a kept frame's
  kFailed,  ///< the re-fusion could not read the base or a kept frame: the map is unchanged
  kCount,   ///< not an outcome: the number of values
};

constexpr size_t kTrajectoryOutcomeCount = static_cast<size_t>(TrajectoryOutcome::kCount);

struct TrajectoryOutcomeInfo {
  TrajectoryOutcome outcome;
  const char* key;    ///< stable snake_case name
  const char* label;  ///< the /diagnostics key of its counter
  bool rejected;      ///< counted among "trajectories rejected"
};
const TrajectoryOutcomeInfo& trajectoryOutcomeInfo(TrajectoryOutcome outcome);

/// One counter per outcome, safe to bump from any thread.
class TrajectoryCounters : public EnumCounters<TrajectoryOutcome, kTrajectoryOutcomeCount> {
 public:
  /// The trajectories refused (the outcomes the table marks `rejected`).
  uint64_t rejected() const;
  /// Calls f(info, count) for every outcome, in the table's order.
  template <typename F>
  void forEach(F&& f) const {
    forEachValue(
        [&](TrajectoryOutcome outcome, uint64_t n) { f(trajectoryOutcomeInfo(outcome), n); });
  }
};

}  // namespace stereo_fusion
