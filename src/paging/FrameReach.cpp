#include "stereo_fusion/paging/FrameReach.h"

namespace stereo_fusion {

FrameReach::FrameReach(const StereoFrame& frame, double far_m, double block_size_m)
    : T_camera_world_(frame.T_world_camera.inverse()), block_size_m_(block_size_m) {
  const StereoCamera& c = frame.camera;
  const double m = 0.5 + kMarginPx;
  // u = fx·x/z + cx ≥ −m  ⇔  fx·x + (cx + m)·z ≥ 0 for z > 0; the four borders together also
  // keep z ≥ 0, and the dilation by one block covers the space around the camera itself.
  planes_[0] = {c.fx(), 0.0, c.cx() + m, 0.0};
  planes_[1] = {-c.fx(), 0.0, c.width() - 1 + m - c.cx(), 0.0};
  planes_[2] = {0.0, c.fy(), c.cy() + m, 0.0};
  planes_[3] = {0.0, -c.fy(), c.height() - 1 + m - c.cy(), 0.0};
  planes_[4] = {0.0, 0.0, -1.0, far_m};
}

bool FrameReach::mayReach(const Eigen::Vector3d& lo_blocks,
                          const Eigen::Vector3d& hi_blocks) const {
  const Eigen::Vector3d lo = (lo_blocks - Eigen::Vector3d::Ones()) * block_size_m_;
  const Eigen::Vector3d hi = (hi_blocks + Eigen::Vector3d::Ones()) * block_size_m_;
  std::array<Eigen::Vector3d, 8> corners;
  for (int i = 0; i < 8; ++i)
    corners[i] = T_camera_world_ * Eigen::Vector3d(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                                                   i & 4 ? hi.z() : lo.z());
  for (const Eigen::Vector4d& p : planes_) {
    bool all_outside = true;
    for (const Eigen::Vector3d& corner : corners)
      if (p.head<3>().dot(corner) + p.w() >= 0.0) {
        all_outside = false;
        break;
      }
    if (all_outside) return false;
  }
  return true;
}

}  // namespace stereo_fusion
