// DisparityNoise on synthetic disparity images with known noise: a plane (disparity affine in
// the pixel) with Gaussian noise, with mismatches and a depth edge, exact, a smooth error the
// estimate cannot see, and an image too small to judge.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <opencv2/core.hpp>

#include "stereo_fusion/integration/DisparityNoise.h"

namespace stereo_fusion {
namespace {

constexpr float kFb = 50.0f;  // f·b, px·m

/// A slanted plane's disparity, 20 + 0.01·u + 0.02·v px, plus `noise(u, v)`.
template <typename Noise>
cv::Mat plane(int width, int height, Noise&& noise) {
  cv::Mat d(height, width, CV_32FC1);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
      d.at<float>(v, u) = static_cast<float>(20.0 + 0.01 * u + 0.02 * v + noise(u, v));
  return d;
}

DisparityNoise measure(const cv::Mat& disparity) {
  ThreadPool pool(1);
  MeasurementImage image;
  image.build(disparity, cv::Mat(), kFb, 0.1f, 100.0f, &pool);
  return measureDisparityNoise(disparity, image);
}

TEST(DisparityNoise, GaussianNoiseOnAPlaneIsMeasured) {
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, 0.3);
  const DisparityNoise n = measure(plane(640, 480, [&](int, int) { return gauss(rng); }));
  // Samples every 4th row and column, 8 px from the sides: 120 rows × 156 columns.
  EXPECT_EQ(n.samples, 120u * 156u);
  EXPECT_NEAR(n.sigma_px, 0.3, 0.015);
}

// 3 % of the pixels off by 1–3 px, and the right half of the image a nearer plane: the median
// ignores them, but each mismatch spoils the three samples it enters (~9 % of them), which
// widens the median absolute deviation by about a tenth.
TEST(DisparityNoise, MismatchesAndADepthEdgeAreTheMinority) {
  std::mt19937 rng(4);
  std::normal_distribution<double> gauss(0.0, 0.25);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const DisparityNoise n = measure(plane(640, 480, [&](int u, int) {
    double e = gauss(rng) + (u >= 320 ? 15.0 : 0.0);
    if (unit(rng) < 0.03) e += (unit(rng) < 0.5 ? -1.0 : 1.0) * (1.0 + 2.0 * unit(rng));
    return e;
  }));
  EXPECT_GT(n.sigma_px, 0.25);
  EXPECT_LT(n.sigma_px, 0.25 * 1.15);
}

// An exact plane measures (almost) nothing; so does a smooth error (0.3 px over 200 px): the
// estimate sees only what varies from pixel to pixel, so it can say "noisier", never "finer".
TEST(DisparityNoise, ExactAndSmoothErrorsReadNearZero) {
  EXPECT_LT(measure(plane(640, 480, [](int, int) { return 0.0; })).sigma_px, 0.005);
  const DisparityNoise smooth =
      measure(plane(640, 480, [](int u, int v) { return 0.3 * std::sin(0.0314 * (u + v)); }));
  EXPECT_LT(smooth.sigma_px, 0.02);
}

TEST(DisparityNoise, TooFewSamplesGiveNoEstimate) {
  const DisparityNoise n = measure(plane(32, 32, [](int, int) { return 0.0; }));
  EXPECT_LT(n.samples, kNoiseMinSamples);
  EXPECT_TRUE(std::isnan(n.sigma_px));
}

}  // namespace
}  // namespace stereo_fusion
