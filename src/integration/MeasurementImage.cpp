#include "stereo_fusion/integration/MeasurementImage.h"

#include <cfloat>
#include <limits>

namespace stereo_fusion {
namespace {

// Both row loops vectorise with the baseline SSE. No AVX2 clone (target_clones): its IFUNC
// resolver runs before ThreadSanitizer's runtime is up and crashed the TSan build, and these
// loops are a small share of the frame (≈ 2 M instructions per VGA frame).

// Branch-free so that the compiler vectorises it: the division is done for every pixel and
// its result discarded where the disparity is unusable (no floating-point traps are enabled).
void convertDepthRow(const float* disparity_px, int width, float fb_px_m, float min_depth_m,
                     float max_depth_m, float* depth_m) {
  const float no_measurement = std::numeric_limits<float>::quiet_NaN();
  for (int u = 0; u < width; ++u) {
    const float d = disparity_px[u];
    const float z = fb_px_m / d;
    // d ≤ FLT_MAX is isfinite(d) once d > 0 (rejects +inf and NaN). `&`, not `&&`: every
    // comparison is evaluated, so there is no branch to keep the compiler from vectorising.
    const bool usable = (d > 0.0f) & (d <= FLT_MAX) & (z >= min_depth_m) & (z <= max_depth_m);
    depth_m[u] = usable ? z : no_measurement;
  }
}

void packColourRow(const uint8_t* color, int channels, int width, uint32_t* rgb) {
  if (channels == 1) {
    for (int u = 0; u < width; ++u) rgb[u] = color[u] * 0x010101u;
    return;
  }
  for (int u = 0; u < width; ++u)
    rgb[u] = color[3 * u] | static_cast<uint32_t>(color[3 * u + 1]) << 8 |
             static_cast<uint32_t>(color[3 * u + 2]) << 16;
}

}  // namespace

void MeasurementImage::build(const cv::Mat& disparity_px, const cv::Mat& color, float fb_px_m,
                             float min_depth_m, float max_depth_m, ThreadPool* pool) {
  width_ = disparity_px.cols;
  height_ = disparity_px.rows;
  const size_t pixels = static_cast<size_t>(width_) * height_;
  depth_m_.resize(pixels);
  if (!color.empty()) rgb_.resize(pixels);
  // ~16 rows per chunk: large enough to amortise the claim, small enough to balance.
  pool->parallelFor(static_cast<size_t>(height_), 16, [&](size_t begin, size_t end) {
    for (size_t v = begin; v < end; ++v) {
      const int row = static_cast<int>(v);
      convertDepthRow(disparity_px.ptr<float>(row), width_, fb_px_m, min_depth_m, max_depth_m,
                      &depth_m_[v * width_]);
      if (!color.empty()) packColourRow(color.ptr<uint8_t>(row), color.channels(), width_, &rgb_[v * width_]);
    }
  });
}

}  // namespace stereo_fusion
