#include "stereo_fusion/camera/StereoCamera.h"

#include <algorithm>

#include <cmath>
#include <sstream>

namespace stereo_fusion {

namespace {
bool finitePositive(double x) { return std::isfinite(x) && x > 0.0; }
}  // namespace

std::optional<StereoCamera> StereoCamera::create(int width_px, int height_px, double fx_px,
                                                 double fy_px, double cx_px, double cy_px,
                                                 double baseline_m, std::string* error) {
  std::ostringstream why;
  if (width_px <= 0 || height_px <= 0) {
    why << "image size must be positive, got " << width_px << "x" << height_px;
  } else if (!finitePositive(fx_px) || !finitePositive(fy_px)) {
    why << "focal lengths must be finite and > 0, got fx=" << fx_px << " fy=" << fy_px;
  } else if (!std::isfinite(cx_px) || !std::isfinite(cy_px)) {
    why << "principal point must be finite, got cx=" << cx_px << " cy=" << cy_px;
  } else if (!finitePositive(baseline_m)) {
    why << "stereo baseline must be finite and > 0 m, got " << baseline_m;
  } else if (fx_px < kMinFocalPerImageSize * std::max(width_px, height_px) ||
             fy_px < kMinFocalPerImageSize * std::max(width_px, height_px)) {
    // A pinhole's focal length is w / (2 tan(FOV / 2)): 0.044 w at a 170° field of view. A broken
    // CameraInfo (fy = 1e-3) would otherwise stretch one frame's points over kilometres.
    why << "focal lengths fx=" << fx_px << " fy=" << fy_px << " px are implausible for a "
        << width_px << "x" << height_px << " image (at least " << kMinFocalPerImageSize << " × "
        << std::max(width_px, height_px) << " px, a field of view under 170°)";
  } else if (!(fx_px / fy_px >= 1.0 / kMaxFocalRatio && fx_px / fy_px <= kMaxFocalRatio)) {
    why << "fx / fy = " << fx_px / fy_px << " is implausible (pixels more than " << kMaxFocalRatio
        << " times wider than high, or the reverse)";
  } else if (std::max(std::abs(cx_px), std::abs(width_px - cx_px)) > kMaxRayTangent * fx_px ||
             std::max(std::abs(cy_px), std::abs(height_px - cy_px)) > kMaxRayTangent * fy_px) {
    why << "principal point cx=" << cx_px << " cy=" << cy_px << " px is implausible for a "
        << width_px << "x" << height_px << " image with fx=" << fx_px << " fy=" << fy_px
        << " (rays more than 85.4° off the optical axis)";
  }
  const std::string reason = why.str();
  if (!reason.empty()) {
    if (error) *error = "invalid stereo camera: " + reason;
    return std::nullopt;
  }
  StereoCamera camera;
  camera.width_px_ = width_px;
  camera.height_px_ = height_px;
  camera.fx_px_ = fx_px;
  camera.fy_px_ = fy_px;
  camera.cx_px_ = cx_px;
  camera.cy_px_ = cy_px;
  camera.baseline_m_ = baseline_m;
  return camera;
}

double StereoCamera::depthFromDisparity(double disparity_px) const {
  if (!(disparity_px > 0.0) || !std::isfinite(disparity_px)) return INFINITY;
  return fx_px_ * baseline_m_ / disparity_px;
}

double StereoCamera::disparityFromDepth(double depth_m) const {
  if (!(depth_m > 0.0) || !std::isfinite(depth_m)) return 0.0;
  return fx_px_ * baseline_m_ / depth_m;
}

Eigen::Vector3d StereoCamera::backProject(double u_px, double v_px, double depth_m) const {
  return {(u_px - cx_px_) * depth_m / fx_px_, (v_px - cy_px_) * depth_m / fy_px_, depth_m};
}

Eigen::Vector3d StereoCamera::backProjectDisparity(double u_px, double v_px,
                                                   double disparity_px) const {
  return backProject(u_px, v_px, depthFromDisparity(disparity_px));
}

bool StereoCamera::project(const Eigen::Vector3d& p_camera, Eigen::Vector2d* uv) const {
  if (!(p_camera.z() > 0.0) || !p_camera.allFinite()) return false;
  const double inv_z = 1.0 / p_camera.z();
  *uv = {fx_px_ * p_camera.x() * inv_z + cx_px_, fy_px_ * p_camera.y() * inv_z + cy_px_};
  return true;
}

bool StereoCamera::isInImage(const Eigen::Vector2d& uv, int border_px) const {
  // Pixel centres sit at integer coordinates; (u, v) belongs to pixel round(u), round(v).
  const double u = std::floor(uv.x() + 0.5);
  const double v = std::floor(uv.y() + 0.5);
  return u >= border_px && v >= border_px && u < width_px_ - border_px &&
         v < height_px_ - border_px;
}

double StereoCamera::depthError(double depth_m, double disparity_error_px) const {
  return depth_m * depth_m / (baseline_m_ * fx_px_) * disparity_error_px;
}

}  // namespace stereo_fusion
