#include "stereo_fusion/integration/DisparityNoise.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace stereo_fusion {

DisparityNoise measureDisparityNoise(const cv::Mat& disparity_px,
                                     const MeasurementImage& measurements) {
  DisparityNoise out;
  const int width = measurements.width(), height = measurements.height();
  const float* depth = measurements.depths();
  const int s = kNoiseSpanPx;
  std::vector<float> second;
  second.reserve(static_cast<size_t>(width / kNoiseSampleStepPx + 1) *
                 (height / kNoiseSampleStepPx + 1));
  for (int v = 0; v < height; v += kNoiseSampleStepPx) {
    const float* d = disparity_px.ptr<float>(v);
    const float* z = depth + static_cast<size_t>(v) * width;
    for (int u = s; u + s < width; u += kNoiseSampleStepPx) {
      if (std::isnan(z[u - s]) || std::isnan(z[u]) || std::isnan(z[u + s])) continue;
      second.push_back(d[u - s] - 2.0f * d[u] + d[u + s]);
    }
  }
  out.samples = second.size();
  if (second.size() < kNoiseMinSamples) {
    out.sigma_px = std::numeric_limits<double>::quiet_NaN();
    return out;
  }
  auto median = [](std::vector<float>* values) {
    std::nth_element(values->begin(), values->begin() + values->size() / 2, values->end());
    return static_cast<double>((*values)[values->size() / 2]);
  };
  const double centre = median(&second);
  for (float& x : second) x = static_cast<float>(std::abs(x - centre));
  out.sigma_px = 1.4826 * median(&second) / std::sqrt(6.0);
  return out;
}

}  // namespace stereo_fusion
