#include "stereo_fusion/session/TrajectoryOutcome.h"

namespace stereo_fusion {

namespace {
constexpr TrajectoryOutcomeInfo kTable[] = {
    {TrajectoryOutcome::kApplied, "applied", "corrections applied", false},
    {TrajectoryOutcome::kAppliedWithoutRefusion, "applied_without_refusion",
     "trajectories taken without re-fusion", false},
    {TrajectoryOutcome::kSuperseded, "superseded", "corrections superseded by a newer trajectory",
     false},
    {TrajectoryOutcome::kDroppedByReset, "dropped_by_reset", "corrections dropped by reset/load",
     false},
    {TrajectoryOutcome::kRejectedWrongFrame, "wrong_frame",
     "trajectories rejected: not in world_frame", true},
    {TrajectoryOutcome::kRejectedNothingKept, "nothing_kept",
     "trajectories rejected: no frame kept (loop_closure_max_frames 0)", true},
    {TrajectoryOutcome::kRejectedNoFrameYet, "no_frame_yet",
     "trajectories rejected: no frame fused yet", true},
    {TrajectoryOutcome::kRejectedNoTransform, "no_transform",
     "trajectories rejected: no transform to the camera", true},
    {TrajectoryOutcome::kRejectedBadPose, "bad_pose", "trajectories rejected: bad pose", true},
    {TrajectoryOutcome::kRejectedEmpty, "empty", "trajectories rejected: no pose", true},
    {TrajectoryOutcome::kRejectedNoMatch, "no_match",
     "trajectories rejected: no stamp near a kept frame", true},
    {TrajectoryOutcome::kFailed, "failed", "corrections failed (map unchanged)", false},
};
static_assert(sizeof(kTable) / sizeof(kTable[0]) == kTrajectoryOutcomeCount,
              "one row per TrajectoryOutcome");

static_assert(rowsFollowEnum(kTable, &TrajectoryOutcomeInfo::outcome),
              "kTable's rows follow TrajectoryOutcome's order");
}  // namespace

const TrajectoryOutcomeInfo& trajectoryOutcomeInfo(TrajectoryOutcome outcome) {
  const size_t k = static_cast<size_t>(outcome);
  return kTable[k < kTrajectoryOutcomeCount ? k : 0];
}

uint64_t TrajectoryCounters::rejected() const {
  uint64_t sum = 0;
  forEach([&](const TrajectoryOutcomeInfo& info, uint64_t n) { sum += info.rejected ? n : 0; });
  return sum;
}

}  // namespace stereo_fusion
