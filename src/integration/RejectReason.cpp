#include "stereo_fusion/integration/RejectReason.h"

namespace stereo_fusion {

namespace {
// In the enum's order (checked below).
constexpr RejectReasonInfo kTable[] = {
    {RejectReason::kNone, "none", "accepted"},
    {RejectReason::kInvalidFrame, "invalid", "dropped: bad input"},
    {RejectReason::kTimestampBackwards, "timestamp_backwards", "dropped: timestamp backwards"},
    {RejectReason::kDuplicateTimestamp, "duplicate", "dropped: duplicate frame"},
    {RejectReason::kPoseJump, "pose_jump", "dropped: pose jump"},
    {RejectReason::kTimestampJump, "timestamp_jump", "dropped: timestamp jump"},
    {RejectReason::kAllocationBudget, "allocation_budget", "dropped: allocation budget"},
    {RejectReason::kIncoherentDisparity, "incoherent_disparity", "dropped: incoherent disparity"},
    {RejectReason::kUnreadable, "unreadable", "dropped: unreadable"},
    {RejectReason::kQueueFull, "queue_full", "dropped: queue full"},
    {RejectReason::kTfTimeout, "tf_timeout", "dropped: tf timeout"},
    {RejectReason::kBadStamp, "bad_stamp", "dropped: bad timestamp"},
    {RejectReason::kSuperseded, "superseded", "dropped: superseded by reset/load"},
    {RejectReason::kSyncDuplicate, "sync_duplicate",
     "dropped: duplicate stamp before synchronisation"},
    {RejectReason::kError, "error", "dropped: error while fusing"},
    {RejectReason::kWorkBound, "work_bound", "dropped: lookup work bound"},
    {RejectReason::kUndecodableImage, "undecodable_image", "dropped: undecodable image"},
};
static_assert(sizeof(kTable) / sizeof(kTable[0]) == kRejectReasonCount, "one row per RejectReason");

static_assert(rowsFollowEnum(kTable, &RejectReasonInfo::reason),
              "kTable's rows follow RejectReason's order");
}  // namespace

const RejectReasonInfo& rejectReasonInfo(RejectReason reason) {
  const size_t k = static_cast<size_t>(reason);
  return kTable[k < kRejectReasonCount ? k : 0];
}

uint64_t RejectCounters::total() const {
  uint64_t sum = 0;
  forEach([&](const RejectReasonInfo&, uint64_t n) { sum += n; });
  return sum;
}

}  // namespace stereo_fusion
