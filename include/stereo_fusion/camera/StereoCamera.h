#pragma once
// Rectified stereo camera model in the ROS convention: left camera optical frame
// (x right, y down, z forward), principal point (cx, cy), baseline to the right camera.

#include <Eigen/Core>
#include <optional>
#include <string>

namespace stereo_fusion {

/// Intrinsics of the LEFT rectified camera plus the stereo baseline.
/// Build it with StereoCamera::create() so invalid values never reach the pipeline.
class StereoCamera {
 public:
  /// An invalid camera (valid() == false); use create() for a real one.
  StereoCamera() = default;
  bool valid() const { return width_px_ > 0; }

  /// Smallest focal length accepted, per pixel of the image's larger side: a pinhole with a
  /// field of view just under 170°.
  static constexpr double kMinFocalPerImageSize = 0.04;
  /// Largest accepted fx / fy (or fy / fx).
  static constexpr double kMaxFocalRatio = 10.0;
  /// Largest |u − cx| / fx (and |v − cy| / fy) of any pixel: the half image over the smallest
  /// focal length kMinFocalPerImageSize allows, 12.5 = tan 85.4°, a ray within the field of
  /// view of the widest lens accepted. The principal point may lie outside the
  /// image (a crop, a shifted rectification), but one kilometres away (K[2] = 1e9) makes every
  /// ray nearly parallel to the image plane and the lookup walk a frustum of absurd size.
  static constexpr double kMaxRayTangent = 0.5 / kMinFocalPerImageSize;

  /// Returns the camera, or std::nullopt with a human-readable reason in `error`.
  /// Rejects non-finite, zero or negative fx, fy, baseline; non-finite cx, cy;
  /// non-positive image size; and implausible calibrations: a focal length below
  /// kMinFocalPerImageSize × the larger image side, fx / fy beyond kMaxFocalRatio, pixels whose
  /// rays lie more than 85.4° off the optical axis (kMaxRayTangent).
  static std::optional<StereoCamera> create(int width_px, int height_px, double fx_px, double fy_px,
                                            double cx_px, double cy_px, double baseline_m,
                                            std::string* error = nullptr);

  int width() const { return width_px_; }
  int height() const { return height_px_; }
  double fx() const { return fx_px_; }
  double fy() const { return fy_px_; }
  double cx() const { return cx_px_; }
  double cy() const { return cy_px_; }
  double baseline() const { return baseline_m_; }

  /// z = f·b / d (thesis §2.2). Non-positive or non-finite disparity → +inf (no surface).
  double depthFromDisparity(double disparity_px) const;
  /// d = f·b / z. Non-positive or non-finite depth → 0 (invalid disparity).
  double disparityFromDepth(double depth_m) const;

  /// Pixel (u, v) with known depth → point in the camera frame:
  /// X = (u − cx)·z/fx, Y = (v − cy)·z/fy, Z = z.
  Eigen::Vector3d backProject(double u_px, double v_px, double depth_m) const;
  /// Same, from disparity (the form the thesis writes as x = −b(u_L+u_R)/(2d) about the rig
  /// centre).
  Eigen::Vector3d backProjectDisparity(double u_px, double v_px, double disparity_px) const;

  /// Camera point → continuous pixel coordinates (eq. 3.12–3.14). Returns false when the point
  /// is not in front of the camera (z ≤ 0) or not finite; `uv` is only written on success.
  bool project(const Eigen::Vector3d& p_camera, Eigen::Vector2d* uv) const;
  /// True when the continuous pixel (u, v) rounds to a pixel inside the image shrunk by
  /// `border_px` on every side.
  bool isInImage(const Eigen::Vector2d& uv, int border_px = 0) const;

  /// Thesis eq. 3.1: depth error e_z = z² / (b·f) · e_d for a disparity error e_d (pixels).
  double depthError(double depth_m, double disparity_error_px) const;

 private:
  int width_px_ = 0;
  int height_px_ = 0;
  double fx_px_ = 0, fy_px_ = 0, cx_px_ = 0, cy_px_ = 0, baseline_m_ = 0;
};

}  // namespace stereo_fusion
