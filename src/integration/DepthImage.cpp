#include "stereo_fusion/integration/DepthImage.h"

#include <cfloat>
#include <limits>

namespace stereo_fusion {
namespace {

// Branch-free so that the compiler vectorises it: the division is done for every pixel and
// its result discarded where the disparity is unusable (no floating-point traps are enabled).
void convertRow(const float* disparity_px, int width, float fb_px_m, float min_depth_m,
                float max_depth_m, float* depth_m) {
  const float no_measurement = std::numeric_limits<float>::quiet_NaN();
  for (int u = 0; u < width; ++u) {
    const float d = disparity_px[u];
    const float z = fb_px_m / d;
    // d ≤ FLT_MAX is isfinite(d) once d > 0 (rejects +inf and NaN).
    const bool usable = d > 0.0f && d <= FLT_MAX && z >= min_depth_m && z <= max_depth_m;
    depth_m[u] = usable ? z : no_measurement;
  }
}

}  // namespace

void DepthImage::build(const cv::Mat& disparity_px, float fb_px_m, float min_depth_m,
                       float max_depth_m, ThreadPool* pool) {
  width_ = disparity_px.cols;
  height_ = disparity_px.rows;
  depth_m_.resize(static_cast<size_t>(width_) * height_);
  // ~16 rows per chunk: large enough to amortise the claim, small enough to balance.
  pool->parallelFor(static_cast<size_t>(height_), 16, [&](size_t begin, size_t end) {
    for (size_t v = begin; v < end; ++v)
      convertRow(disparity_px.ptr<float>(static_cast<int>(v)), width_, fb_px_m, min_depth_m,
                 max_depth_m, &depth_m_[v * width_]);
  });
}

}  // namespace stereo_fusion
