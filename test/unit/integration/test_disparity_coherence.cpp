// DisparityCoherence: hand-counted small images, thread-count independence, and the two
// populations it separates (a rendered surface with stereo noise; random disparities).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <opencv2/core.hpp>

#include "../MeshTestSupport.h"
#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/integration/DisparityCoherence.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

/// z = 1 / d, usable depths 0.25..4 m: disparities 0.25..4 px are usable.
DisparityCoherence coherenceOf(const cv::Mat& disparity, int threads = 1) {
  ThreadPool pool(threads);
  MeasurementImage m;
  m.build(disparity, cv::Mat(), 1.0f, 0.25f, 4.0f, &pool);
  return measureDisparityCoherence(disparity, m, &pool);
}

}  // namespace

TEST(DisparityCoherence, HandCountedRows) {
  // 1.0 and 1.5 agree (|0.5| ≤ 0.5); 2.01 is 0.51 from 1.5 and agrees with nothing.
  cv::Mat row = (cv::Mat_<float>(1, 3) << 1.0f, 1.5f, 2.01f);
  DisparityCoherence c = coherenceOf(row);
  EXPECT_EQ(c.usable_pixels, 3u);
  EXPECT_EQ(c.coherent_pixels, 2u);
  EXPECT_DOUBLE_EQ(c.share(), 2.0 / 3.0);

  // A neighbour that is not usable does not count, however close its value: 0.2 px is beyond
  // 4 m (z = 5 m), NaN and 0 are no measurement.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cv::Mat lonely = (cv::Mat_<float>(3, 3) << 0.2f, nan, 0.0f, nan, 0.45f, 0.2f, 0.0f, 3.9f, nan);
  c = coherenceOf(lonely);
  EXPECT_EQ(c.usable_pixels, 2u) << "0.45 and 3.9";
  EXPECT_EQ(c.coherent_pixels, 0u);
  EXPECT_DOUBLE_EQ(c.share(), 0.0);

  // Diagonal neighbours count; a uniform block is all coherent.
  cv::Mat diagonal = (cv::Mat_<float>(2, 2) << 2.0f, 3.0f, 0.0f, 2.2f);
  c = coherenceOf(diagonal);
  EXPECT_EQ(c.usable_pixels, 3u);
  EXPECT_EQ(c.coherent_pixels, 2u) << "2.0 and 2.2 (diagonal) agree; 3.0 is 0.8 from both";
  c = coherenceOf(cv::Mat(4, 5, CV_32F, cv::Scalar(1.0f)));
  EXPECT_EQ(c.usable_pixels, 20u);
  EXPECT_EQ(c.coherent_pixels, 20u);
  EXPECT_DOUBLE_EQ(coherenceOf(cv::Mat(2, 2, CV_32F, cv::Scalar(0.0f))).share(), 1.0)
      << "nothing usable";
}

TEST(DisparityCoherence, CountsDoNotDependOnTheThreads) {
  cv::Mat noise(97, 61, CV_32F);
  cv::RNG rng(3);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 5.0);
  const DisparityCoherence one = coherenceOf(noise, 1);
  for (int threads : {2, 3, 8}) {
    const DisparityCoherence many = coherenceOf(noise, threads);
    EXPECT_EQ(many.usable_pixels, one.usable_pixels) << threads;
    EXPECT_EQ(many.coherent_pixels, one.coherent_pixels) << threads;
  }
}

// Against the rule written out pixel by pixel: a usable pixel is coherent if a usable one of
// its 8 neighbours is within the tolerance. Random disparities near the tolerance, a quarter of
// them unusable (0, NaN or beyond the depth range), on an image whose inside and border the
// function treats apart.
TEST(DisparityCoherence, CountsTheRuleWrittenOutPixelByPixel) {
  cv::Mat disparity(53, 71, CV_32F);
  cv::RNG rng(11);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < disparity.rows; ++v)
    for (int u = 0; u < disparity.cols; ++u) {
      const int kind = rng.uniform(0, 12);
      disparity.at<float>(v, u) = kind == 0   ? 0.0f
                                  : kind == 1 ? nan
                                  : kind == 2 ? 0.1f  // 10 m: beyond 4 m
                                              : 1.0f + rng.uniform(0.0f, 1.2f);
    }
  auto usable = [&](int v, int u) {
    const float d = disparity.at<float>(v, u);
    return d >= 0.25f && d <= 4.0f;  // z = 1 / d within 0.25..4 m
  };
  size_t usable_pixels = 0, coherent_pixels = 0;
  for (int v = 0; v < disparity.rows; ++v)
    for (int u = 0; u < disparity.cols; ++u) {
      if (!usable(v, u)) continue;
      ++usable_pixels;
      bool agrees = false;
      for (int nv = v - 1; nv <= v + 1; ++nv)
        for (int nu = u - 1; nu <= u + 1; ++nu)
          if ((nv != v || nu != u) && nv >= 0 && nu >= 0 && nv < disparity.rows &&
              nu < disparity.cols && usable(nv, nu) &&
              std::fabs(disparity.at<float>(nv, nu) - disparity.at<float>(v, u)) <=
                  kCoherenceTolerancePx)
            agrees = true;
      coherent_pixels += agrees;
    }
  const DisparityCoherence c = coherenceOf(disparity, 2);
  EXPECT_EQ(c.usable_pixels, usable_pixels);
  EXPECT_EQ(c.coherent_pixels, coherent_pixels);
  EXPECT_GT(coherent_pixels, usable_pixels / 4);
  EXPECT_LT(coherent_pixels, usable_pixels);
}

TEST(DisparityCoherence, SeparatesANoisySurfaceFromRandomDisparities) {
  // A rendered floor and sphere with 0.3 px of Gaussian disparity noise (twice the default
  // disparity_noise_px) against disparities drawn uniformly over 1–64 px.
  const StereoFrame surface =
      renderFrame(floorAndSphere(), qvgaCamera(), floorAndSphereView(0), 0.3, 1);
  ThreadPool pool(2);
  MapperConfig config;
  MeasurementImage m;
  m.build(surface, stageConfigs(config).pipeline.measurement, &pool);
  const double surface_share = measureDisparityCoherence(surface.disparity_px, m, &pool).share();
  EXPECT_GT(surface_share, 0.95);

  cv::Mat random(surface.disparity_px.size(), CV_32F);
  cv::RNG rng(7);
  rng.fill(random, cv::RNG::UNIFORM, 1.0, 64.0);
  StereoFrame broken = surface;
  broken.disparity_px = random;
  m.build(broken, stageConfigs(config).pipeline.measurement, &pool);
  const double random_share = measureDisparityCoherence(random, m, &pool).share();
  // Chance agreement with one of 8 neighbours within ±0.5 px over 63 px: 1 − (1 − 1/63)⁸ ≈ 12 %.
  EXPECT_NEAR(random_share, 1.0 - std::pow(1.0 - 1.0 / 63.0, 8), 0.02);
  EXPECT_LT(random_share, config.min_coherent_pixel_share);
  EXPECT_GT(surface_share, config.min_coherent_pixel_share);
}
