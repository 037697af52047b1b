#include "stereo_fusion/integration/OutlierRejection.h"

#include <limits>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace stereo_fusion {
namespace {

// filterSpeckles' marker for "no disparity": below every usable value (they are > 0).
constexpr int16_t kNoDisparity16 = -16;

}  // namespace

OutlierRejectionStats OutlierRejection::apply(const cv::Mat& disparity_px,
                                              const OutlierConfig& config,
                                              MeasurementImage* measurements, ThreadPool* pool) {
  OutlierRejectionStats stats;
  CV_Assert(disparity_px.type() == CV_32FC1 && disparity_px.rows == measurements->height() &&
            disparity_px.cols == measurements->width());
  const int width = measurements->width(), height = measurements->height();
  const float* depth_m = measurements->depths();  // NaN where unusable

  if (config.speckle_max_area_px > 0) {
    const cv::Mat depth(height, width, CV_32FC1, const_cast<float*>(depth_m));
    cv::compare(depth, depth, usable_, cv::CMP_EQ);  // NaN ≠ NaN: exactly the usable pixels
    // Saturating conversion; values beyond 2047 px saturate together, far nearer than any
    // usable depth of a real camera.
    disparity_px.convertTo(fixed_point_, CV_16S, 16.0);
    fixed_point_.setTo(kNoDisparity16, ~usable_);
    cv::filterSpeckles(fixed_point_, kNoDisparity16, config.speckle_max_area_px,
                       config.speckle_max_diff_px * 16.0, speckle_buffer_);
    cv::compare(fixed_point_, kNoDisparity16, reject_, cv::CMP_EQ);
    stats.speckle_pixels =
        measurements->invalidate(reject_, pool);  // counts only pixels that were usable
  }
  if (config.edge_reject_radius_px > 0) {
    masked_.create(height, width, CV_32FC1);
    const float unusable = std::numeric_limits<float>::infinity();
    parallelForOrHere(pool, static_cast<size_t>(height), 32, [&](size_t begin, size_t end) {
      for (int v = static_cast<int>(begin); v < static_cast<int>(end); ++v) {
        const float* d = disparity_px.ptr<float>(v);
        const float* z = depth_m + static_cast<size_t>(v) * width;
        float* out = masked_.ptr<float>(v);
        for (int u = 0; u < width; ++u) out[u] = z[u] == z[u] ? d[u] : unusable;
      }
    });
    const int side = 2 * config.edge_reject_radius_px + 1;
    // erode = the window's minimum (the farthest usable disparity); outside the image it
    // counts as +inf, so borders reject nothing by themselves.
    cv::erode(masked_, farthest_, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(side, side)));
    reject_.create(height, width, CV_8UC1);
    const float jump_px = static_cast<float>(config.edge_reject_jump_px);
    parallelForOrHere(pool, static_cast<size_t>(height), 32, [&](size_t begin, size_t end) {
      for (int v = static_cast<int>(begin); v < static_cast<int>(end); ++v) {
        const float* d = masked_.ptr<float>(v);
        const float* far = farthest_.ptr<float>(v);
        uint8_t* out = reject_.ptr<uint8_t>(v);
        // inf − inf is NaN and fails the compare: unusable pixels are never rejected.
        for (int u = 0; u < width; ++u) out[u] = d[u] - far[u] > jump_px ? 255 : 0;
      }
    });
    stats.edge_pixels = measurements->invalidate(reject_, pool);
  }
  return stats;
}

}  // namespace stereo_fusion
