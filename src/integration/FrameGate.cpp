#include "stereo_fusion/integration/FrameGate.h"

#include <iomanip>
#include <sstream>

namespace stereo_fusion {

FrameGate::FrameGate(const FrameGateLimits& limits) : limits_(limits) {}

RejectReason FrameGate::judge(const Seen& reference, const Seen& frame, std::string* why) const {
  std::ostringstream os;
  os << std::setprecision(9);
  if (limits_.require_increasing_timestamps && frame.timestamp_s != 0.0 &&
      reference.timestamp_s != 0.0) {
    if (frame.timestamp_s < reference.timestamp_s) {
      os << "timestamp " << frame.timestamp_s << " s goes backwards (last fused frame at "
         << reference.timestamp_s << " s)";
      *why = os.str();
      return RejectReason::kTimestampBackwards;
    }
    if (frame.timestamp_s == reference.timestamp_s) {
      os << "duplicate frame: timestamp " << frame.timestamp_s << " s was already fused";
      *why = os.str();
      return RejectReason::kDuplicateTimestamp;
    }
  }
  if (limits_.max_timestamp_gap_s > 0.0 && frame.timestamp_s != 0.0 &&
      reference.timestamp_s != 0.0 &&
      frame.timestamp_s - reference.timestamp_s > limits_.max_timestamp_gap_s) {
    os << "timestamp " << frame.timestamp_s << " s is " << frame.timestamp_s - reference.timestamp_s
       << " s after the last fused frame (max_timestamp_gap_s = " << limits_.max_timestamp_gap_s
       << ")";
    *why = os.str();
    return RejectReason::kTimestampJump;
  }
  if (limits_.max_pose_jump_m > 0.0) {
    const double jump_m = (frame.position_m - reference.position_m).norm();
    if (jump_m > limits_.max_pose_jump_m) {
      os << "camera jumped " << jump_m
         << " m since the last fused frame (max_pose_jump_m = " << limits_.max_pose_jump_m << ")";
      *why = os.str();
      return RejectReason::kPoseJump;
    }
  }
  return RejectReason::kNone;
}

RejectReason FrameGate::check(const StereoFrame& frame, std::string* why, bool* reanchored) {
  if (reanchored) *reanchored = false;
  const Seen seen{frame.timestamp_s, frame.T_world_camera.translation()};
  Seen reference;
  reference.timestamp_s = last_fused_timestamp_s_.value_or(0.0);
  // Without a fused position yet there is nothing to jump from: the frame is its own reference.
  reference.position_m = last_fused_position_m_.value_or(seen.position_m);
  const RejectReason reason = judge(reference, seen, why);
  if (reason == RejectReason::kNone) {
    rejected_run_.clear();
    return reason;
  }
  // A duplicate is the same moment again, never a new reference.
  if (reason == RejectReason::kDuplicateTimestamp) return reason;
  std::string unused;
  if (!rejected_run_.empty() && judge(rejected_run_.back(), seen, &unused) != RejectReason::kNone)
    rejected_run_.clear();
  rejected_run_.push_back(seen);
  if (static_cast<int>(rejected_run_.size()) < kFramesToReanchor) return reason;
  rejected_run_.clear();
  if (reanchored) *reanchored = true;
  *why += "; the last " + std::to_string(kFramesToReanchor) +
          " frames agree with each other (a relocalisation or a clock reset): accepted as the new "
          "reference";
  return RejectReason::kNone;
}

void FrameGate::accepted(const StereoFrame& frame) {
  if (frame.timestamp_s != 0.0) last_fused_timestamp_s_ = frame.timestamp_s;
  last_fused_position_m_ = frame.T_world_camera.translation();
}

void FrameGate::reset() {
  last_fused_timestamp_s_.reset();
  last_fused_position_m_.reset();
  rejected_run_.clear();
}

}  // namespace stereo_fusion
