#include "stereo_fusion/paging/FrameReach.h"

#include <algorithm>
#include <cmath>

namespace stereo_fusion {

FrameReach::FrameReach(const StereoFrame& frame, double max_depth_m, double band_m,
                       double unmeasured_m, double block_size_m)
    : T_camera_world_(frame.T_world_camera.inverse()),
      camera_(frame.camera),
      block_size_m_(block_size_m) {
  const StereoCamera& c = frame.camera;
  tiles_x_ = (c.width() + kTilePx - 1) / kTilePx;
  tiles_y_ = (c.height() + kTilePx - 1) / kTilePx;
  tile_far_m_.assign(static_cast<size_t>(tiles_x_) * tiles_y_, -1.0f);
  // The smallest disparity of each tile is its farthest depth; a pixel without a match
  // reaches unmeasured_m (the free space it counts as seeing), if that is on.
  std::vector<float> min_disparity(tile_far_m_.size(), 0.0f);
  std::vector<char> unmatched(tile_far_m_.size(), 0);
  const cv::Mat& disparity = frame.disparity_px;
  for (int v = 0; v < disparity.rows; ++v) {
    const float* row = disparity.ptr<float>(v);
    const size_t tile_row = static_cast<size_t>(v / kTilePx) * tiles_x_;
    for (int u = 0; u < disparity.cols; ++u) {
      const size_t t = tile_row + u / kTilePx;
      const float d = row[u];
      if (std::isfinite(d) && d > 0.0f) {
        if (min_disparity[t] == 0.0f || d < min_disparity[t]) min_disparity[t] = d;
      } else {
        unmatched[t] = 1;
      }
    }
  }
  for (size_t t = 0; t < tile_far_m_.size(); ++t) {
    double far = -1.0;
    if (min_disparity[t] > 0.0f)
      far = std::min(c.depthFromDisparity(min_disparity[t]), max_depth_m) + band_m;
    if (unmatched[t] && unmeasured_m > 0.0) far = std::max(far, unmeasured_m + band_m);
    tile_far_m_[t] = static_cast<float>(far);
    far_m_ = std::max(far_m_, far);
  }
  const double m = 0.5 + kMarginPx;
  // u = fx·x/z + cx ≥ −m  ⇔  fx·x + (cx + m)·z ≥ 0 for z > 0; the four borders together also
  // keep z ≥ 0, and the dilation by one block covers the space around the camera itself.
  planes_[0] = {c.fx(), 0.0, c.cx() + m, 0.0};
  planes_[1] = {-c.fx(), 0.0, c.width() - 1 + m - c.cx(), 0.0};
  planes_[2] = {0.0, c.fy(), c.cy() + m, 0.0};
  planes_[3] = {0.0, -c.fy(), c.height() - 1 + m - c.cy(), 0.0};
  planes_[4] = {0.0, 0.0, -1.0, far_m_};
}

bool FrameReach::inFrustum(const std::array<Eigen::Vector3d, 8>& corners) const {
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

bool FrameReach::mayReach(const Eigen::Vector3d& lo_blocks,
                          const Eigen::Vector3d& hi_blocks) const {
  if (far_m_ < 0.0) return false;  // a frame without a pixel that reaches anything
  const Eigen::Vector3d lo = (lo_blocks - Eigen::Vector3d::Ones()) * block_size_m_;
  const Eigen::Vector3d hi = (hi_blocks + Eigen::Vector3d::Ones()) * block_size_m_;
  std::array<Eigen::Vector3d, 8> corners;
  double z_min = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 8; ++i) {
    corners[i] = T_camera_world_ * Eigen::Vector3d(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                                                   i & 4 ? hi.z() : lo.z());
    z_min = std::min(z_min, corners[i].z());
  }
  if (!inFrustum(corners)) return false;
  // A box reaching to the image plane or behind it: the frustum test decides (its corners'
  // projections bound nothing there).
  constexpr double kMinDepthM = 1e-3;
  if (z_min < kMinDepthM) return true;
  // In front of the camera the box projects inside its corners' projections: it may reach
  // what a tile overlapping them (widened by the margin) measures no nearer than the box.
  double u_min = std::numeric_limits<double>::infinity(), u_max = -u_min;
  double v_min = u_min, v_max = -u_min;
  for (const Eigen::Vector3d& p : corners) {
    const double u = camera_.fx() * p.x() / p.z() + camera_.cx();
    const double v = camera_.fy() * p.y() / p.z() + camera_.cy();
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    v_min = std::min(v_min, v);
    v_max = std::max(v_max, v);
  }
  const double m = 0.5 + kMarginPx;
  const int tx0 = std::max(0, static_cast<int>(std::floor((u_min - m) / kTilePx)));
  const int tx1 = std::min(tiles_x_ - 1, static_cast<int>(std::floor((u_max + m) / kTilePx)));
  const int ty0 = std::max(0, static_cast<int>(std::floor((v_min - m) / kTilePx)));
  const int ty1 = std::min(tiles_y_ - 1, static_cast<int>(std::floor((v_max + m) / kTilePx)));
  for (int ty = ty0; ty <= ty1; ++ty)
    for (int tx = tx0; tx <= tx1; ++tx)
      if (tile_far_m_[static_cast<size_t>(ty) * tiles_x_ + tx] >= z_min) return true;
  return false;
}

}  // namespace stereo_fusion
