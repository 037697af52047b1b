#pragma once
#include <Eigen/Geometry>
#include <vector>

#include "stereo_fusion/integration/StereoFrame.h"

namespace stereo_fusion {

/// A camera pose at a time: T_world_camera at `stamp_s`.
struct StampedPose {
  double stamp_s = 0.0;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
};

/// Sorts `poses` by increasing stamp (what PoseCorrection and originalPoseAt() expect).
void sortByStamp(std::vector<StampedPose>* poses);

/// The pose halfway between `a` and `b` at `alpha` ∈ [0, 1]: translation linear, rotation slerp.
Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                                  double alpha);

/// Where a SLAM's revised trajectory puts frames that were fused at their original poses.
///
/// Each trajectory pose k (stamp t_k, corrected camera pose T_k) implies a correction of the
/// world, C_k = T_k · O(t_k)⁻¹, with O(t) the original pose at t (the fused frames' poses,
/// interpolated between the two frames around t). A frame fused at stamp s with original pose
/// O_s moves to C(s) · O_s, with C(s):
///   - between two trajectory poses: their corrections interpolated (interpolatePose());
///   - before the first: the first's correction;
///   - after the last: the last's correction if the frame was fused before the trajectory
///     arrived (`stamp_s <= extrapolate_until_s`: it shares the drift the SLAM removed), and
///     none otherwise (the SLAM's poses of later frames are already corrected).
/// Trajectory poses more than `max_gap_s` from every fused frame imply no correction (nothing
/// fused there to compare with) and are skipped.
class PoseCorrection {
 public:
  /// No correction: every pose stays.
  PoseCorrection() = default;
  /// `fused`: the frames' original poses, by increasing stamp; `trajectory`: the corrected
  /// poses, by increasing stamp.
  PoseCorrection(const std::vector<StampedPose>& fused, const std::vector<StampedPose>& trajectory,
                 double extrapolate_until_s, double max_gap_s = 0.5);

  /// True if at least one trajectory pose implied a correction.
  bool empty() const { return corrections_.empty(); }
  /// C(stamp_s) as above (the identity when empty()).
  Eigen::Isometry3d correctionAt(double stamp_s) const;
  /// C(stamp_s) · T_world_camera_original.
  Eigen::Isometry3d corrected(double stamp_s,
                              const Eigen::Isometry3d& T_world_camera_original) const {
    return correctionAt(stamp_s) * T_world_camera_original;
  }
  /// `frame` (fused at its pose) at its corrected pose; the images are shared, not copied.
  StereoFrame corrected(const StereoFrame& frame) const {
    StereoFrame moved = frame;
    moved.T_world_camera = corrected(frame.timestamp_s, frame.T_world_camera);
    return moved;
  }
  /// The corrections C_k, by stamp (for tests and logs).
  const std::vector<StampedPose>& corrections() const { return corrections_; }

 private:
  std::vector<StampedPose> corrections_;  // C_k in T_world_camera, by stamp
  double extrapolate_until_s_ = 0.0;
};

/// The original pose O(t) of `fused` (by increasing stamp) at `stamp_s`, interpolated between the
/// two frames around it; false if no fused frame lies within `max_gap_s` of it on a side it
/// needs (before the first or after the last frame by more than max_gap_s, or in a gap of the
/// frames wider than 2·max_gap_s).
bool originalPoseAt(const std::vector<StampedPose>& fused, double stamp_s, double max_gap_s,
                    Eigen::Isometry3d* pose);

/// The largest move of a camera centre (m) and rotation (deg) that `correction` gives `originals`.
void correctionMagnitude(const std::vector<StampedPose>& originals,
                         const PoseCorrection& correction, double* shift_m, double* rotation_deg);

}  // namespace stereo_fusion
