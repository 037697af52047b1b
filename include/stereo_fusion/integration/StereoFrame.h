#pragma once
#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>
#include <string>

#include "stereo_fusion/camera/StereoCamera.h"

namespace stereo_fusion {

/// One stereo measurement, ready to fuse.
struct StereoFrame {
  double timestamp_s = 0.0;
  /// Rectified left disparity, CV_32FC1, pixels. Values ≤ 0 or non-finite mean "no match".
  cv::Mat disparity_px;
  /// Rectified left image, CV_8UC3 in RGB order or CV_8UC1 grey, same size; may be empty.
  cv::Mat color;
  /// Pose of the left camera's optical frame: maps camera points into the world.
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  StereoCamera camera;
  /// The source's disparity resolution in px (DisparityImage.delta_d; 0 = unknown): coarse
  /// steps add their rounding error to the disparity noise that picks the levels.
  double disparity_step_px = 0.0;
};

/// The coarsest disparity resolution a frame may claim (px).
constexpr double kMaxDisparityStepPx = 4.0;

/// Empty string when `frame` can be fused; otherwise one sentence saying what is wrong
/// (image types and sizes, camera, pose finiteness and orthonormality, pose range).
std::string validateFrame(const StereoFrame& frame, double block_size_m);

}  // namespace stereo_fusion
