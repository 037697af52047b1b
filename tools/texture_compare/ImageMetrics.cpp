#include "texture_compare/ImageMetrics.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace stereo_fusion::texcmp {

double SquaredError::psnrDb() const {
  if (values == 0) return 0.0;
  const double mse = sum / values;
  return mse > 0 ? 10.0 * std::log10(255.0 * 255.0 / mse) : INFINITY;
}

SquaredError squaredError(const cv::Mat& image, const cv::Mat& truth, const cv::Mat& mask) {
  SquaredError e;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      if (!mask.at<uint8_t>(y, x)) continue;
      const cv::Vec3b& a = image.at<cv::Vec3b>(y, x);
      const cv::Vec3b& b = truth.at<cv::Vec3b>(y, x);
      for (int k = 0; k < 3; ++k) {
        const double d = static_cast<double>(a[k]) - b[k];
        e.sum += d * d;
      }
      e.values += 3;
    }
  return e;
}

GradientEnergy gradientEnergy(const cv::Mat& image_rgb, const cv::Mat& mask) {
  cv::Mat grey, gx, gy, inner;
  cv::cvtColor(image_rgb, grey, cv::COLOR_RGB2GRAY);
  grey.convertTo(grey, CV_32F);
  // Sobel's 3×3 kernel weighs the central difference by 4 (1-2-1 smoothing, ±1 taps): scale
  // by 1/8 so a ramp of one grey level per pixel has gradient 1.
  cv::Sobel(grey, gx, CV_32F, 1, 0, 3, 1.0 / 8.0);
  cv::Sobel(grey, gy, CV_32F, 0, 1, 3, 1.0 / 8.0);
  cv::erode(mask, inner, cv::Mat::ones(3, 3, CV_8U), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT,
            cv::Scalar(0));
  GradientEnergy g;
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x) {
      if (!inner.at<uint8_t>(y, x)) continue;
      const double dx = gx.at<float>(y, x), dy = gy.at<float>(y, x);
      g.sum += dx * dx + dy * dy;
      ++g.pixels;
    }
  return g;
}

}  // namespace stereo_fusion::texcmp
