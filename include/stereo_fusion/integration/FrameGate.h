#pragma once
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "stereo_fusion/integration/RejectReason.h"
#include "stereo_fusion/integration/StereoFrame.h"

namespace stereo_fusion {

/// Limits of FrameGate; 0 (or false) disables a check.
struct FrameGateLimits {
  double max_pose_jump_m = 0.0;
  double max_timestamp_gap_s = 0.0;
  bool require_increasing_timestamps = false;
};

/// Checks a well-formed frame against the last FUSED frame: time order, time gap and pose
/// continuity. A rejected frame never becomes the reference, so one glitch (a pose 1 km away, a
/// stamp in the year 2001 or 2050) costs exactly that frame. A lasting change (a SLAM
/// relocalisation, a clock reset) shows as consecutive rejected frames that agree with each
/// other (stamps increasing within the gap, cameras within max_pose_jump_m of each other): the
/// kFramesToReanchor-th such frame is accepted and becomes the new reference ("re-anchored").
/// Timestamp 0 means unknown: it is neither ordered nor a reference for time.
class FrameGate {
 public:
  /// Rejected frames that must agree with each other before the gate follows them.
  static constexpr int kFramesToReanchor = 3;

  explicit FrameGate(const FrameGateLimits& limits);

  /// kNone when `frame` may be fused; otherwise the reason, with one sentence in `why`.
  /// `*reanchored` (if given) is set when the frame is accepted only by re-anchoring.
  RejectReason check(const StereoFrame& frame, std::string* why, bool* reanchored = nullptr);
  /// Call once the frame was fused: it becomes the reference.
  void accepted(const StereoFrame& frame);
  /// Forgets the history (map reset or load).
  void reset();
  /// The camera position of the last fused frame (none yet: nullopt).
  const std::optional<Eigen::Vector3d>& lastFusedPosition() const { return last_fused_position_m_; }

 private:
  struct Seen {
    double timestamp_s = 0.0;  // 0: unknown
    Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  };
  /// The reason `frame` does not follow `reference` (kNone if it does), with `why`.
  RejectReason judge(const Seen& reference, const Seen& frame, std::string* why) const;

  FrameGateLimits limits_;
  std::optional<double> last_fused_timestamp_s_;
  std::optional<Eigen::Vector3d> last_fused_position_m_;
  std::vector<Seen> rejected_run_;  // consecutive rejected frames that agree with each other
};

}  // namespace stereo_fusion
