#pragma once
// A depth camera's image (REP 118: 16UC1 in millimetres, 32FC1 in metres) as the disparity of
// a virtual rectified stereo rig, d = fx·B/z, so that the core fuses it like stereo: the core
// turns it back into z = fx·B/d exactly (to float rounding) and reads B only for its noise
// model, σ_z = z²·σ_d/(fx·B) (doc/method.md#depth-cameras).

#include <cstddef>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

namespace stereo_fusion {

struct DepthConversionConfig {
  /// Baseline of the virtual stereo rig (m): the depth camera's own (its stereo pair's, or its
  /// projector's to its camera), so that σ_z = z²·σ_d/(fx·B) is its depth error.
  double baseline_m = 0.05;
};

/// One message per out-of-range value (empty = valid).
std::vector<std::string> validateDepthConversionConfig(const DepthConversionConfig& config);

/// A depth image's bytes as a driver sends them (nothing is copied).
struct DepthImageView {
  std::string encoding;  ///< "16UC1" or "mono16" (mm), "32FC1" (m)
  int width = 0, height = 0;
  size_t step_bytes = 0;  ///< bytes per row
  bool big_endian = false;
  const uint8_t* data = nullptr;
  size_t size_bytes = 0;
};

class DepthToDisparity {
 public:
  /// `config` must be valid (validateDepthConversionConfig()).
  explicit DepthToDisparity(DepthConversionConfig config) : config_(config) {}
  double baselineM() const { return config_.baseline_m; }

  /// The disparity (CV_32FC1, px) of `depth` for a camera of focal length `fx_px`: fx·B/z where
  /// z is a measurement, 0 (no match) where it is not: 0 mm in 16UC1; NaN, ±inf or z ≤ 0 in
  /// 32FC1. False with one sentence in `error` (and `disparity_px` untouched) for an encoding
  /// other than these, an empty image, a step or data too short for its size, or fx not > 0.
  bool convert(const DepthImageView& depth, double fx_px, cv::Mat* disparity_px,
               std::string* error) const;

 private:
  DepthConversionConfig config_;
};

}  // namespace stereo_fusion
