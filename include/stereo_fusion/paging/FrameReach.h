#pragma once
#include <array>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fusion/integration/StereoFrame.h"

namespace stereo_fusion {

/// Where a frame can change the map, as a test on boxes of whole blocks: the camera's frustum
/// (the image widened by kMarginPx on every side), out to the depth each tile of kTilePx² pixels
/// measures plus the widest truncation band (`band_m`), capped at max_depth_m. Every block the
/// lookup can queue (the pixels' ray segments to depth + Φ, 0.75 px around the ray), that
/// fusion can create and that carving can visit (in front of a measured depth) lies in it, and
/// the mesher reads at most one block beyond a changed one: so a paged map that brings back
/// every block within one block of it before a frame fuses it exactly as if nothing had been
/// paged out. Bounded by what the pixels measure, not by max_depth_m, it stops at the walls a
/// camera looks at: a frame in a corridor does not bring back the rooms behind them.
class FrameReach {
 public:
  static constexpr double kMarginPx = 2.0;
  static constexpr int kTilePx = 16;

  /// `max_depth_m`: the farthest depth fusion keeps; `band_m`: the widest truncation band;
  /// `unmeasured_m` (> 0): how far a pixel without a measurement counts as seeing free space.
  FrameReach(const StereoFrame& frame, double max_depth_m, double band_m, double unmeasured_m,
             double block_size_m);
  /// False only when no block within one block of the box [lo, hi) (block units) is in reach.
  bool mayReach(const Eigen::Vector3d& lo_blocks, const Eigen::Vector3d& hi_blocks) const;
  /// The farthest depth any tile reaches (its test's far plane).
  double farM() const { return far_m_; }

 private:
  /// The plane test against the whole frustum out to far_m_ (a box that reaches behind the
  /// image plane, where projecting its corners says nothing).
  bool inFrustum(const std::array<Eigen::Vector3d, 8>& corners) const;

  std::array<Eigen::Vector4d, 5> planes_;  // (a, d): a·p_camera + d ≥ 0 inside
  Eigen::Isometry3d T_camera_world_;
  StereoCamera camera_;
  double block_size_m_;
  double far_m_ = 0.0;
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<float> tile_far_m_;  // per tile, row-major; negative: the tile reaches nothing
};

}  // namespace stereo_fusion
