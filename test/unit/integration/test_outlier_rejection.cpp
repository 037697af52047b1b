// OutlierRejection on images whose answer is counted by hand: a fattened foreground square on a
// background plane, slanted planes at the steepest disparity gradient a plane can have, isolated
// speckles of known size, unusable pixels next to usable ones, both rules off.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <opencv2/core.hpp>

#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/integration/OutlierRejection.h"

using namespace stereo_fusion;

namespace {

constexpr float kFb = 50.0f;  // f·b (px·m): d = 10 px is 5 m, d = 20 px is 2.5 m
constexpr int kWidth = 64, kHeight = 48;

MapperConfig rejectionConfig(int speckle_area_px, int edge_radius_px) {
  MapperConfig config;
  config.min_depth_m = 0.1;
  config.max_depth_m = 100.0;
  config.speckle_max_area_px = speckle_area_px;
  config.speckle_max_diff_px = 1.0;
  config.edge_reject_radius_px = edge_radius_px;
  config.edge_reject_jump_px = 1.0;
  return config;
}

struct Rejected {
  OutlierRejectionStats stats;
  cv::Mat usable;  // CV_8U, 1 where the measurement image keeps a depth
};

Rejected reject(const cv::Mat& disparity, const MapperConfig& config) {
  ThreadPool pool(1);
  MeasurementImage image;
  image.build(disparity, cv::Mat(), kFb, static_cast<float>(config.min_depth_m),
              static_cast<float>(config.max_depth_m), &pool);
  OutlierRejection rejection;
  Rejected r;
  r.stats = rejection.apply(disparity, stageConfigs(config).pipeline.outliers, &image);
  r.usable = cv::Mat::zeros(disparity.size(), CV_8U);
  for (int v = 0; v < disparity.rows; ++v)
    for (int u = 0; u < disparity.cols; ++u) {
      const float z = image.depths()[v * disparity.cols + u];
      if (!std::isnan(z)) {
        r.usable.at<uint8_t>(v, u) = 1;
        EXPECT_EQ(z, kFb / disparity.at<float>(v, u))
            << "a kept depth changed at (" << u << ", " << v << ")";
      }
    }
  return r;
}

}  // namespace

TEST(OutlierRejection, DropsTheNearSideOfADepthEdgeAndKeepsTheFarSide) {
  // Background at 10 px; a foreground square of 12 × 12 px at 20 px (SGBM's fattening already
  // in it). With radius 2 a foreground pixel is dropped if a background pixel is within 2 px
  // (Chebyshev): the square's outer ring two pixels wide, 12² − 8² = 80 pixels. No background
  // pixel has a farther neighbour.
  cv::Mat disparity(kHeight, kWidth, CV_32FC1, cv::Scalar(10.0f));
  const cv::Rect square(20, 15, 12, 12);
  disparity(square).setTo(20.0f);
  const Rejected r = reject(disparity, rejectionConfig(0, 2));
  EXPECT_EQ(r.stats.edge_pixels, 80u);
  EXPECT_EQ(r.stats.speckle_pixels, 0u);
  EXPECT_EQ(cv::countNonZero(r.usable(square)), 8 * 8);
  EXPECT_EQ(cv::countNonZero(r.usable), kWidth * kHeight - 80);
  // Radius 1: the ring one pixel wide, 12² − 10² = 44.
  EXPECT_EQ(reject(disparity, rejectionConfig(0, 1)).stats.edge_pixels, 44u);
}

TEST(OutlierRejection, AStepOfAtMostTheJumpIsNoEdge) {
  // Steps of exactly 1 px (the jump) are kept; 1.01 px is an edge.
  cv::Mat disparity(kHeight, kWidth, CV_32FC1, cv::Scalar(10.0f));
  disparity(cv::Rect(0, 0, kWidth / 2, kHeight)).setTo(11.0f);
  EXPECT_EQ(reject(disparity, rejectionConfig(0, 2)).stats.edge_pixels, 0u);
  disparity(cv::Rect(0, 0, kWidth / 2, kHeight)).setTo(11.01f);
  // The two columns left of the step, every row.
  EXPECT_EQ(reject(disparity, rejectionConfig(0, 2)).stats.edge_pixels,
            static_cast<uint64_t>(2 * kHeight));
}

TEST(OutlierRejection, KeepsSlantedPlanesUpToTheJumpOverTheRadius) {
  // A road 1.65 m below a 0.54 m baseline: d grows by b/h = 0.327 px per image row; over the
  // radius of 2 rows 0.65 px < 1 px. A plane at the steepest gradient 1/radius = 0.5 px per
  // row is kept too; 0.55 px per row (1.1 px over 2) is cut everywhere but the last rows.
  for (const float gradient : {0.327f, 0.5f}) {
    cv::Mat disparity(kHeight, kWidth, CV_32FC1);
    for (int v = 0; v < kHeight; ++v) disparity.row(v).setTo(5.0f + gradient * v);
    EXPECT_EQ(reject(disparity, rejectionConfig(50, 2)).stats.edge_pixels, 0u)
        << "gradient " << gradient;
    EXPECT_EQ(reject(disparity, rejectionConfig(50, 2)).stats.speckle_pixels, 0u)
        << "gradient " << gradient;
  }
  cv::Mat steep(kHeight, kWidth, CV_32FC1);
  for (int v = 0; v < kHeight; ++v) steep.row(v).setTo(5.0f + 0.55f * v);
  // Row v is cut by row v − 2 (1.1 px farther): every row but the first two.
  EXPECT_EQ(reject(steep, rejectionConfig(0, 2)).stats.edge_pixels,
            static_cast<uint64_t>((kHeight - 2) * kWidth));
}

TEST(OutlierRejection, DropsSpecklesUpToTheirAreaAndNoLargerBlob) {
  // A 3 × 3 blob at 30 px and a 1-pixel blob at 3 px on a 10 px plane: 10 pixels of speckle.
  cv::Mat disparity(kHeight, kWidth, CV_32FC1, cv::Scalar(10.0f));
  disparity(cv::Rect(10, 10, 3, 3)).setTo(30.0f);
  disparity.at<float>(30, 40) = 3.0f;
  Rejected r = reject(disparity, rejectionConfig(9, 0));
  EXPECT_EQ(r.stats.speckle_pixels, 10u);
  EXPECT_EQ(cv::countNonZero(r.usable(cv::Rect(10, 10, 3, 3))), 0);
  EXPECT_EQ(r.usable.at<uint8_t>(30, 40), 0);
  // Area 8: the 3 × 3 blob is larger and stays; the single pixel goes.
  r = reject(disparity, rejectionConfig(8, 0));
  EXPECT_EQ(r.stats.speckle_pixels, 1u);
  EXPECT_EQ(cv::countNonZero(r.usable(cv::Rect(10, 10, 3, 3))), 9);
  // A blob whose values step by at most speckle_max_diff_px is one blob with the plane.
  cv::Mat ramp(kHeight, kWidth, CV_32FC1, cv::Scalar(10.0f));
  ramp(cv::Rect(10, 10, 3, 3)).setTo(11.0f);
  EXPECT_EQ(reject(ramp, rejectionConfig(9, 0)).stats.speckle_pixels, 0u);
}

TEST(OutlierRejection, UnusablePixelsNeitherRejectNorCountAsBlobs) {
  // Holes (0, NaN, beyond max_depth_m) next to a plane cut nothing; a plane region walled in by
  // holes is a blob of its own size.
  cv::Mat disparity(kHeight, kWidth, CV_32FC1, cv::Scalar(10.0f));
  disparity(cv::Rect(0, 0, 20, kHeight)).setTo(0.0f);
  disparity(cv::Rect(20, 0, 5, kHeight)).setTo(std::numeric_limits<float>::quiet_NaN());
  disparity(cv::Rect(25, 0, 5, kHeight)).setTo(0.4f);  // 125 m, beyond max_depth_m
  Rejected r = reject(disparity, rejectionConfig(50, 2));
  EXPECT_EQ(r.stats.edge_pixels, 0u);
  EXPECT_EQ(r.stats.speckle_pixels, 0u);
  EXPECT_EQ(cv::countNonZero(r.usable), (kWidth - 30) * kHeight);
  // A 6 × 6 island surrounded by holes: 36 pixels, a speckle at area 36, kept at 35.
  cv::Mat island(kHeight, kWidth, CV_32FC1, cv::Scalar(0.0f));
  island(cv::Rect(30, 20, 6, 6)).setTo(10.0f);
  EXPECT_EQ(reject(island, rejectionConfig(36, 0)).stats.speckle_pixels, 36u);
  EXPECT_EQ(reject(island, rejectionConfig(35, 0)).stats.speckle_pixels, 0u);
}

TEST(OutlierRejection, BothRulesOffChangeNothing) {
  cv::Mat disparity(kHeight, kWidth, CV_32FC1, cv::Scalar(10.0f));
  disparity(cv::Rect(20, 15, 12, 12)).setTo(20.0f);
  disparity.at<float>(30, 40) = 3.0f;
  const Rejected r = reject(disparity, rejectionConfig(0, 0));
  EXPECT_EQ(r.stats.edge_pixels + r.stats.speckle_pixels, 0u);
  EXPECT_EQ(cv::countNonZero(r.usable), kWidth * kHeight);
}

// The per-pixel passes run in row bands on a pool: the same depths and counts as on one thread,
// on a large image of random steps (many edges, speckles and unusable pixels).
TEST(OutlierRejection, ThePoolsRowBandsGiveTheSameResultAsOneThread) {
  cv::Mat disparity(480, 640, CV_32FC1);
  cv::RNG rng(7);
  for (int v = 0; v < disparity.rows; ++v)
    for (int u = 0; u < disparity.cols; ++u) {
      const int cell = (v / 5) * 131 + (u / 7);  // piecewise constant patches, then noise
      disparity.at<float>(v, u) =
          (cell % 11 == 0) ? 0.0f : 5.0f + static_cast<float>(cell % 17) + rng.uniform(0.0f, 0.3f);
    }
  const MapperConfig config = rejectionConfig(20, 1);
  ThreadPool one(1), two(2);
  MeasurementImage serial, banded;
  serial.build(disparity, cv::Mat(), kFb, 0.1f, 100.0f, &one);
  banded.build(disparity, cv::Mat(), kFb, 0.1f, 100.0f, &one);
  OutlierRejection a, b;
  const OutlierRejectionStats s =
      a.apply(disparity, stageConfigs(config).pipeline.outliers, &serial);
  const OutlierRejectionStats p =
      b.apply(disparity, stageConfigs(config).pipeline.outliers, &banded, &two);
  EXPECT_GT(s.edge_pixels, 1000u);
  EXPECT_EQ(p.edge_pixels, s.edge_pixels);
  EXPECT_EQ(p.speckle_pixels, s.speckle_pixels);
  const size_t n = static_cast<size_t>(disparity.rows) * disparity.cols;
  size_t same = 0;
  for (size_t i = 0; i < n; ++i) {
    const float x = serial.depths()[i], y = banded.depths()[i];
    same += (std::isnan(x) && std::isnan(y)) || x == y;
  }
  EXPECT_EQ(same, n);
}
