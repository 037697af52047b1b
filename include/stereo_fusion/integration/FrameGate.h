#pragma once
#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "stereo_fusion/integration/StereoFrame.h"

namespace stereo_fusion {

/// Why a frame was not fused; the ROS diagnostics and stats.json count frames by this.
enum class RejectReason {
  kNone,                ///< accepted
  kInvalidFrame,        ///< validateFrame() failed: images, camera or pose malformed
  kTimestampBackwards,  ///< timestamp before the last fused frame's
  kDuplicateTimestamp,  ///< timestamp equal to the last fused frame's
  kPoseJump,            ///< camera moved more than max_pose_jump_m since the previous frame
};

/// Short stable name of a reason, e.g. "timestamp_backwards" (counter keys, stats.json).
const char* rejectReasonName(RejectReason reason);

/// Checks a well-formed frame against the frames before it: time order and pose continuity.
/// It remembers the last fused timestamp and the previous frame's camera position; a frame
/// rejected for a pose jump still becomes "the previous frame", so a lasting relocalisation
/// costs one frame and a one-frame glitch two, instead of locking the map out forever.
class FrameGate {
 public:
  /// `max_pose_jump_m` 0 disables the jump check; `require_increasing_timestamps` false
  /// disables the time order check.
  FrameGate(double max_pose_jump_m, bool require_increasing_timestamps);

  /// kNone when `frame` may be fused; otherwise the reason, with one sentence in `why`.
  /// Records the frame's camera position as "previous" for the next jump check.
  RejectReason check(const StereoFrame& frame, std::string* why);
  /// Call once the frame was fused: it becomes the reference for the time order.
  void accepted(const StereoFrame& frame);
  /// Forgets the history (map reset or load).
  void reset();

 private:
  double max_pose_jump_m_;
  bool require_increasing_timestamps_;
  std::optional<double> last_fused_timestamp_s_;
  std::optional<Eigen::Vector3d> previous_position_m_;
};

}  // namespace stereo_fusion
