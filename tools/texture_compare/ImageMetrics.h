#pragma once
// Photometric error and sharpness of a rendered image against ground truth, over a mask.

#include <opencv2/core/mat.hpp>

namespace stereo_fusion::texcmp {

/// Sum of squared differences over the masked pixels (all three channels) and their count.
struct SquaredError {
  double sum = 0;
  size_t values = 0;  ///< pixels × 3 channels
  /// PSNR in dB for 8-bit images: 10·log10(255² / MSE); +inf for identical images.
  double psnrDb() const;
};

/// Squared error of CV_8UC3 `image` against CV_8UC3 `truth` where `mask` (CV_8UC1) is non-zero.
SquaredError squaredError(const cv::Mat& image, const cv::Mat& truth, const cv::Mat& mask);

/// Sharpness: mean of |∇I|² of the grey image (0.299 R + 0.587 G + 0.114 B, 3×3 Sobel,
/// grey levels per pixel squared) over the mask eroded by one pixel, so no gradient reaches
/// outside the mask. Returns the sum and the pixel count to pool views.
struct GradientEnergy {
  double sum = 0;
  size_t pixels = 0;
  double mean() const { return pixels ? sum / pixels : 0.0; }
};
GradientEnergy gradientEnergy(const cv::Mat& image_rgb, const cv::Mat& mask);

}  // namespace stereo_fusion::texcmp
