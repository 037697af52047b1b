#pragma once
#include <array>

#include <Eigen/Geometry>

#include "stereo_fusion/integration/StereoFrame.h"

namespace stereo_fusion {

/// Where a frame can change the map, as a test on boxes of whole blocks: the camera's frustum
/// (the image widened by kMarginPx on every side, out to `far_m`). Every block the lookup can
/// queue (the pixels' ray segments to depth + Φ, 0.75 px around the ray), that fusion can
/// create and that carving can visit lies in it, and the mesher reads at most one block beyond
/// a changed one: so a paged map that brings back every block within one block of the frustum
/// before a frame fuses it exactly as if nothing had been paged out.
class FrameReach {
 public:
  static constexpr double kMarginPx = 2.0;

  /// `far_m`: max_depth_m plus the widest truncation band.
  FrameReach(const StereoFrame& frame, double far_m, double block_size_m);
  /// False only when no block within one block of the box [lo, hi) (block units) is in the
  /// frustum.
  bool mayReach(const Eigen::Vector3d& lo_blocks, const Eigen::Vector3d& hi_blocks) const;

 private:
  std::array<Eigen::Vector4d, 5> planes_;  // (a, d): a·p_camera + d ≥ 0 inside
  Eigen::Isometry3d T_camera_world_;
  double block_size_m_;
};

}  // namespace stereo_fusion
