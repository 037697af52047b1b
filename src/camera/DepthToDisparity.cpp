#include "stereo_fusion/camera/DepthToDisparity.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace stereo_fusion {

namespace {

constexpr bool kHostBigEndian = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;

/// The value of type T at `bytes`, in host order.
template <typename T>
T readValue(const uint8_t* bytes, bool swap) {
  uint8_t copy[sizeof(T)];
  std::memcpy(copy, bytes, sizeof(T));
  if (swap) std::reverse(copy, copy + sizeof(T));
  T value;
  std::memcpy(&value, copy, sizeof(T));
  return value;
}

}  // namespace

std::vector<std::string> validateDepthConversionConfig(const DepthConversionConfig& config) {
  std::vector<std::string> errors;
  if (!(std::isfinite(config.baseline_m) && config.baseline_m > 0.0 && config.baseline_m <= 10.0))
    errors.push_back("'depth_baseline_m' must be in (0, 10] m, got " +
                     std::to_string(config.baseline_m));
  return errors;
}

bool DepthToDisparity::convert(const DepthImageView& depth, double fx_px, cv::Mat* disparity_px,
                               std::string* error) const {
  const bool millimetres = depth.encoding == "16UC1" || depth.encoding == "mono16";
  const bool metres = depth.encoding == "32FC1";
  if (!millimetres && !metres) {
    *error = "depth encoding must be 16UC1 (or mono16; millimetres) or 32FC1 (metres), got '" +
             depth.encoding + "'";
    return false;
  }
  const size_t value_bytes = millimetres ? 2 : 4;
  if (depth.width <= 0 || depth.height <= 0 || depth.data == nullptr) {
    *error = "depth image is empty (" + std::to_string(depth.width) + "x" +
             std::to_string(depth.height) + ")";
    return false;
  }
  if (depth.step_bytes < static_cast<size_t>(depth.width) * value_bytes ||
      depth.size_bytes < depth.step_bytes * static_cast<size_t>(depth.height)) {
    *error = "depth image data (" + std::to_string(depth.size_bytes) + " bytes, step " +
             std::to_string(depth.step_bytes) + ") is shorter than " + std::to_string(depth.width) +
             "x" + std::to_string(depth.height) + " values of " + std::to_string(value_bytes) +
             " bytes";
    return false;
  }
  if (!(std::isfinite(fx_px) && fx_px > 0.0)) {
    *error = "depth camera fx must be finite and > 0, got " + std::to_string(fx_px);
    return false;
  }
  // d = fx·B/z in double, rounded once to float: the core's z = fx·B/d comes back within a
  // float's rounding of the measured z.
  const double f_b = fx_px * config_.baseline_m;
  const bool swap = depth.big_endian != kHostBigEndian;
  cv::Mat out(depth.height, depth.width, CV_32FC1);
  for (int v = 0; v < depth.height; ++v) {
    const uint8_t* row = depth.data + static_cast<size_t>(v) * depth.step_bytes;
    float* d = out.ptr<float>(v);
    for (int u = 0; u < depth.width; ++u) {
      const uint8_t* at = row + static_cast<size_t>(u) * value_bytes;
      const double z_m = millimetres ? 1e-3 * readValue<uint16_t>(at, swap)
                                     : static_cast<double>(readValue<float>(at, swap));
      d[u] = std::isfinite(z_m) && z_m > 0.0 ? static_cast<float>(f_b / z_m) : 0.0f;
    }
  }
  *disparity_px = out;
  return true;
}

}  // namespace stereo_fusion
