#pragma once
#include <cstddef>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// The surface depth z = f·b/d (eq. 3.1) of every pixel of one disparity frame, converted once
/// per frame so that the voxels of all blocks that project onto a pixel share one division
/// and one set of range checks. NaN marks a pixel without a usable measurement: no match
/// (d ≤ 0 or not finite) or a depth outside [min_depth_m, max_depth_m]. A valid depth is never
/// NaN, so "is NaN" is the whole validity test.
///
/// The buffer is kept across frames: rebuilding for a frame of the same size allocates nothing.
class DepthImage {
 public:
  /// Fills the image from `disparity_px` (CV_32FC1, any row stride) with z = fb_px_m / d,
  /// the very float expression of the fuser, so depths are bit-identical to a per-voxel
  /// division. Rows are converted in parallel on `pool`.
  void build(const cv::Mat& disparity_px, float fb_px_m, float min_depth_m, float max_depth_m,
             ThreadPool* pool);

  int width() const { return width_; }
  int height() const { return height_; }
  /// Row-major depths, width() per row, no padding.
  const float* data() const { return depth_m_.data(); }
  float at(int u, int v) const { return depth_m_[static_cast<size_t>(v) * width_ + u]; }

 private:
  std::vector<float> depth_m_;
  int width_ = 0;
  int height_ = 0;
};

}  // namespace stereo_fusion
