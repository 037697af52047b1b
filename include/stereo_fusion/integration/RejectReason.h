#pragma once
#include <cstddef>
#include <cstdint>

#include "stereo_fusion/util/EnumCounters.h"

namespace stereo_fusion {

/// Why a frame did not reach the map: the one list of reasons. The Mapper gives the first ones
/// (validation and its FrameGate), the session and its inputs the rest. /diagnostics, stats.json
/// and the demo name and count frames by this (rejectReasonInfo()); a new reason is one enum
/// value and one row of the table in RejectReason.cpp.
enum class RejectReason : uint8_t {
  kNone,                 ///< accepted
  kInvalidFrame,         ///< validateFrame() failed: images, camera or pose malformed
  kTimestampBackwards,   ///< timestamp before the last fused frame's
  kDuplicateTimestamp,   ///< timestamp equal to the last fused frame's
  kPoseJump,             ///< camera moved more than max_pose_jump_m since the last fused frame
  kTimestampJump,        ///< timestamp more than max_timestamp_gap_s after the last fused frame's
  kAllocationBudget,     ///< its bands reach more new blocks than max_new_blocks_per_frame
  kIncoherentDisparity,  ///< fewer usable disparities agree with a neighbour than
                         ///< min_coherent_pixel_share
  kUnreadable,           ///< the dataset frame could not be read (offline)
  kQueueFull,            ///< the frame queue was full (queue_size, drop_oldest)
  kTfTimeout,            ///< no camera pose from tf within tf_timeout_s
  kBadStamp,             ///< stamped 0, or ahead of the clock by more than max_stamp_ahead_s
  kSuperseded,        ///< arrived before a reset or load_map: it belongs to the map they replaced
  kSyncDuplicate,     ///< a second disparity of a stamp whose frame was not matched yet
  kError,             ///< fusing it threw (e.g. out of memory); the mesh was rebuilt from the map
  kWorkBound,         ///< its band boxes would make the lookup visit more than
                      ///< max_lookup_blocks_per_frame blocks (an absurd calibration or range)
  kUndecodableImage,  ///< its image or depth image came compressed and did not decode
  kCount,             ///< not a reason: the number of values
};

constexpr size_t kRejectReasonCount = static_cast<size_t>(RejectReason::kCount);

struct RejectReasonInfo {
  RejectReason reason;
  const char* key;    ///< stable snake_case name: stats.json `frames.skipped_by_reason`, logs
  const char* label;  ///< the /diagnostics key of its counter
};

/// The row of `reason` in the table.
const RejectReasonInfo& rejectReasonInfo(RejectReason reason);
/// Short stable name of a reason, e.g. "timestamp_backwards" (rejectReasonInfo().key).
inline const char* rejectReasonName(RejectReason reason) { return rejectReasonInfo(reason).key; }

/// One counter per reason, safe to bump from any thread.
class RejectCounters : public EnumCounters<RejectReason, kRejectReasonCount> {
 public:
  /// Every frame dropped, whatever the reason.
  uint64_t total() const;
  /// Calls f(info, count) for every reason but kNone, in the table's order.
  template <typename F>
  void forEach(F&& f) const {
    forEachValue([&](RejectReason reason, uint64_t n) {
      if (reason != RejectReason::kNone) f(rejectReasonInfo(reason), n);
    });
  }
};

}  // namespace stereo_fusion
