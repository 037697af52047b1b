#include "stereo_fusion/integration/StereoFrame.h"

#include <opencv2/core.hpp>
#include <sstream>

#include "stereo_fusion/map/BlockOctree.h"

namespace stereo_fusion {

std::string validateFrame(const StereoFrame& frame, double block_size_m) {
  std::ostringstream why;
  const StereoCamera& cam = frame.camera;
  if (!cam.valid()) return "camera model is not set (zero image size or intrinsics)";
  if (frame.disparity_px.empty()) return "disparity image is empty";
  if (!(frame.disparity_step_px >= 0.0 && frame.disparity_step_px <= kMaxDisparityStepPx))
    return "disparity step (DisparityImage.delta_d) of " + std::to_string(frame.disparity_step_px) +
           " px is not a resolution in [0, " +
           std::to_string(static_cast<int>(kMaxDisparityStepPx)) + "] px";
  if (frame.disparity_px.type() != CV_32FC1)
    return "disparity image must be CV_32FC1 (float pixels), got type " +
           std::to_string(frame.disparity_px.type());
  if (frame.disparity_px.cols != cam.width() || frame.disparity_px.rows != cam.height()) {
    why << "disparity is " << frame.disparity_px.cols << "x" << frame.disparity_px.rows
        << " but the camera is " << cam.width() << "x" << cam.height();
    return why.str();
  }
  if (!frame.color.empty()) {
    if (frame.color.type() != CV_8UC3 && frame.color.type() != CV_8UC1)
      return "colour image must be 8-bit RGB or grey, got type " +
             std::to_string(frame.color.type());
    if (frame.color.size() != frame.disparity_px.size()) {
      why << "colour image is " << frame.color.cols << "x" << frame.color.rows
          << " but disparity is " << frame.disparity_px.cols << "x" << frame.disparity_px.rows;
      return why.str();
    }
  }
  const Eigen::Matrix4d& m = frame.T_world_camera.matrix();
  if (!m.allFinite()) return "camera pose T_world_camera is not finite";
  const Eigen::Matrix3d r = frame.T_world_camera.linear();
  const double orthonormality_error =
      (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthonormality_error > 1e-3 || r.determinant() < 0.0) {
    why << "camera pose rotation is not a rotation (|RᵀR − I| = " << orthonormality_error
        << ", det = " << r.determinant() << ")";
    return why.str();
  }
  if (m.block<1, 3>(3, 0).cwiseAbs().maxCoeff() > 1e-9 || std::abs(m(3, 3) - 1.0) > 1e-9)
    return "camera pose is not a rigid transform (last row is not 0 0 0 1)";
  const double max_coordinate_m = block_size_m * (BlockOctree::kMaxKey / 2);
  if (frame.T_world_camera.translation().cwiseAbs().maxCoeff() > max_coordinate_m) {
    why << "camera position " << frame.T_world_camera.translation().transpose()
        << " m is beyond the map's range of ±" << max_coordinate_m << " m";
    return why.str();
  }
  return {};
}

}  // namespace stereo_fusion
