#pragma once
#include <cstddef>

#include <opencv2/core/mat.hpp>

#include "stereo_fusion/integration/MeasurementImage.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// A usable disparity within this of a usable 8-neighbour's agrees with it (px).
constexpr float kCoherenceTolerancePx = 0.5f;
/// Frames with fewer usable pixels are not judged (too few to tell noise from a surface).
constexpr size_t kCoherenceMinUsablePixels = 64;

/// How much of a frame's disparity image is spatially coherent. A matcher's output is piecewise
/// smooth and its speckle filter removes isolated values: on KITTI SGBM, 7-Scenes depth and the
/// simulator's SGBM frames 99.8–100 % of usable pixels agree with a neighbour within 0.5 px.
/// Disparities drawn at random over R px agree with one of 8 neighbours by chance about
/// 8/R of the time (12 % over 0–64 px): a broken matcher, a wrong topic or a corrupt message,
/// whose frame would put a point anywhere along every ray.
struct DisparityCoherence {
  size_t usable_pixels = 0;    ///< with a usable measurement (MeasurementImage depth not NaN)
  size_t coherent_pixels = 0;  ///< usable, with a usable 8-neighbour within kCoherenceTolerancePx
  /// coherent / usable; 1 when nothing is usable.
  double share() const {
    return usable_pixels == 0
               ? 1.0
               : static_cast<double>(coherent_pixels) / static_cast<double>(usable_pixels);
  }
};

/// Counts the usable and coherent pixels of `disparity_px` (CV_32FC1), usable as `measurements`
/// (built from it) says; rows in parallel on `pool`. The counts do not depend on the threads.
DisparityCoherence measureDisparityCoherence(const cv::Mat& disparity_px,
                                             const MeasurementImage& measurements,
                                             ThreadPool* pool);

}  // namespace stereo_fusion
