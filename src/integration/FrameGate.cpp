#include "stereo_fusion/integration/FrameGate.h"

#include <iomanip>
#include <sstream>

namespace stereo_fusion {

const char* rejectReasonName(RejectReason reason) {
  switch (reason) {
    case RejectReason::kNone: return "none";
    case RejectReason::kInvalidFrame: return "invalid";
    case RejectReason::kTimestampBackwards: return "timestamp_backwards";
    case RejectReason::kDuplicateTimestamp: return "duplicate";
    case RejectReason::kPoseJump: return "pose_jump";
  }
  return "unknown";
}

FrameGate::FrameGate(double max_pose_jump_m, bool require_increasing_timestamps)
    : max_pose_jump_m_(max_pose_jump_m), require_increasing_timestamps_(require_increasing_timestamps) {}

RejectReason FrameGate::check(const StereoFrame& frame, std::string* why) {
  std::ostringstream os;
  os << std::setprecision(9);
  // Timestamp 0 is "unknown" (synthetic frames, re-fusing a frame on purpose): not ordered.
  if (require_increasing_timestamps_ && frame.timestamp_s != 0.0 && last_fused_timestamp_s_) {
    if (frame.timestamp_s < *last_fused_timestamp_s_) {
      os << "timestamp " << frame.timestamp_s << " s goes backwards (last fused frame at "
         << *last_fused_timestamp_s_ << " s)";
      *why = os.str();
      return RejectReason::kTimestampBackwards;
    }
    if (frame.timestamp_s == *last_fused_timestamp_s_) {
      os << "duplicate frame: timestamp " << frame.timestamp_s << " s was already fused";
      *why = os.str();
      return RejectReason::kDuplicateTimestamp;
    }
  }
  const Eigen::Vector3d position = frame.T_world_camera.translation();
  const std::optional<Eigen::Vector3d> previous = previous_position_m_;
  previous_position_m_ = position;
  if (max_pose_jump_m_ > 0.0 && previous) {
    const double jump_m = (position - *previous).norm();
    if (jump_m > max_pose_jump_m_) {
      os << "camera jumped " << jump_m << " m since the previous frame (max_pose_jump_m = "
         << max_pose_jump_m_ << ")";
      *why = os.str();
      return RejectReason::kPoseJump;
    }
  }
  return RejectReason::kNone;
}

void FrameGate::accepted(const StereoFrame& frame) {
  if (frame.timestamp_s != 0.0) last_fused_timestamp_s_ = frame.timestamp_s;
}

void FrameGate::reset() {
  last_fused_timestamp_s_.reset();
  previous_position_m_.reset();
}

}  // namespace stereo_fusion
