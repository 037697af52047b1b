#pragma once
#include <cstddef>

#include <opencv2/core/mat.hpp>

#include "stereo_fusion/integration/MeasurementImage.h"

namespace stereo_fusion {

/// Every this many rows and columns a sample; the second difference spans ±this many pixels,
/// beyond the matching window, so the errors of its three disparities are independent.
constexpr int kNoiseSampleStepPx = 4;
constexpr int kNoiseSpanPx = 8;
/// Fewer samples than this: no estimate (NaN).
constexpr size_t kNoiseMinSamples = 500;

/// The source's disparity noise σ_d measured on one frame, from the frame alone. A plane's
/// disparity is an affine function of the pixel, so its second difference along a row,
/// d(u − s) − 2·d(u) + d(u + s), is zero but for the noise, whose variance it holds six times
/// over. σ_d = 1.4826 · MAD / √6 over the usable samples (s = kNoiseSpanPx): depth edges,
/// curved surfaces and a matcher's mismatches are the minority a median ignores. Poses play
/// no part, so a drifting pose cannot read as noise.
struct DisparityNoise {
  double sigma_px = 0.0;  ///< NaN with fewer than kNoiseMinSamples samples
  size_t samples = 0;
};

/// On `disparity_px` (CV_32FC1) where `measurements` (built from it) has a usable depth.
DisparityNoise measureDisparityNoise(const cv::Mat& disparity_px,
                                     const MeasurementImage& measurements);

}  // namespace stereo_fusion
