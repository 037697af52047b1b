#include "stereo_fusion/trajectory/PoseCorrection.h"

#include <algorithm>
#include <cmath>

namespace stereo_fusion {

void sortByStamp(std::vector<StampedPose>* poses) {
  std::sort(poses->begin(), poses->end(),
            [](const StampedPose& a, const StampedPose& b) { return a.stamp_s < b.stamp_s; });
}

Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                                  double alpha) {
  const Eigen::Quaterniond qa(a.rotation()), qb(b.rotation());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = qa.slerp(alpha, qb).normalized().toRotationMatrix();
  out.translation() = (1.0 - alpha) * a.translation() + alpha * b.translation();
  return out;
}

namespace {
bool byStamp(const StampedPose& p, double stamp_s) { return p.stamp_s < stamp_s; }
}  // namespace

bool originalPoseAt(const std::vector<StampedPose>& fused, double stamp_s, double max_gap_s,
                    Eigen::Isometry3d* pose) {
  if (fused.empty()) return false;
  const auto after = std::lower_bound(fused.begin(), fused.end(), stamp_s, byStamp);
  if (after == fused.begin()) {
    if (after->stamp_s - stamp_s > max_gap_s) return false;
    *pose = after->T_world_camera;
    return true;
  }
  const auto before = after - 1;
  if (after == fused.end()) {
    if (stamp_s - before->stamp_s > max_gap_s) return false;
    *pose = before->T_world_camera;
    return true;
  }
  const double span_s = after->stamp_s - before->stamp_s;
  if (span_s > 2.0 * max_gap_s) return false;
  const double alpha = span_s > 0.0 ? (stamp_s - before->stamp_s) / span_s : 0.0;
  *pose = interpolatePose(before->T_world_camera, after->T_world_camera, alpha);
  return true;
}

PoseCorrection::PoseCorrection(const std::vector<StampedPose>& fused,
                               const std::vector<StampedPose>& trajectory,
                               double extrapolate_until_s, double max_gap_s)
    : extrapolate_until_s_(extrapolate_until_s) {
  for (const StampedPose& corrected : trajectory) {
    Eigen::Isometry3d original;
    if (!originalPoseAt(fused, corrected.stamp_s, max_gap_s, &original)) continue;
    corrections_.push_back({corrected.stamp_s, corrected.T_world_camera * original.inverse()});
  }
}

Eigen::Isometry3d PoseCorrection::correctionAt(double stamp_s) const {
  if (corrections_.empty()) return Eigen::Isometry3d::Identity();
  const auto after = std::lower_bound(corrections_.begin(), corrections_.end(), stamp_s, byStamp);
  if (after == corrections_.begin()) return after->T_world_camera;
  if (after == corrections_.end())
    return stamp_s <= extrapolate_until_s_ ? corrections_.back().T_world_camera
                                           : Eigen::Isometry3d::Identity();
  const auto before = after - 1;
  const double span_s = after->stamp_s - before->stamp_s;
  const double alpha = span_s > 0.0 ? (stamp_s - before->stamp_s) / span_s : 0.0;
  return interpolatePose(before->T_world_camera, after->T_world_camera, alpha);
}

void correctionMagnitude(const std::vector<StampedPose>& originals,
                         const PoseCorrection& correction, double* shift_m, double* rotation_deg) {
  *shift_m = 0.0;
  *rotation_deg = 0.0;
  for (const StampedPose& original : originals) {
    const Eigen::Isometry3d moved = correction.corrected(original.stamp_s, original.T_world_camera);
    *shift_m =
        std::max(*shift_m, (moved.translation() - original.T_world_camera.translation()).norm());
    const Eigen::AngleAxisd turn(
        (moved.linear() * original.T_world_camera.linear().transpose()).eval());
    *rotation_deg = std::max(*rotation_deg, std::abs(turn.angle()) * 180.0 / M_PI);
  }
}

}  // namespace stereo_fusion
