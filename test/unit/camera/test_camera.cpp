#include <gtest/gtest.h>

#include "stereo_fusion/camera/StereoCamera.h"

using stereo_fusion::StereoCamera;

namespace {
StereoCamera camera() { return *StereoCamera::create(640, 480, 500.0, 480.0, 320.0, 240.0, 0.1); }
}  // namespace

TEST(StereoCamera, DepthFromDisparityHandWorked) {
  // z = f·b/d = 500 · 0.1 / 25 = 2.0 m
  EXPECT_DOUBLE_EQ(camera().depthFromDisparity(25.0), 2.0);
  EXPECT_DOUBLE_EQ(camera().disparityFromDepth(2.0), 25.0);
  EXPECT_DOUBLE_EQ(camera().depthFromDisparity(50.0), 1.0);
}

TEST(StereoCamera, InvalidDisparityMeansNoSurface) {
  EXPECT_TRUE(std::isinf(camera().depthFromDisparity(0.0)));
  EXPECT_TRUE(std::isinf(camera().depthFromDisparity(-3.0)));
  EXPECT_TRUE(std::isinf(camera().depthFromDisparity(NAN)));
  EXPECT_EQ(camera().disparityFromDepth(0.0), 0.0);
  EXPECT_EQ(camera().disparityFromDepth(INFINITY), 0.0);
}

TEST(StereoCamera, BackProjectHandWorked) {
  // X = (420 − 320)·2/500 = 0.4, Y = (180 − 240)·2/480 = −0.25, Z = 2
  const Eigen::Vector3d p = camera().backProject(420, 180, 2.0);
  EXPECT_NEAR(p.x(), 0.4, 1e-12);
  EXPECT_NEAR(p.y(), -0.25, 1e-12);
  EXPECT_NEAR(p.z(), 2.0, 1e-12);
  const Eigen::Vector3d q = camera().backProjectDisparity(420, 180, 25.0);
  EXPECT_NEAR((p - q).norm(), 0.0, 1e-12);
}

TEST(StereoCamera, MatchesThesisRigCentreForm) {
  // Thesis: x = −b(u_L + u_R)/(2d) about the rig centre, u from the principal point, x to the
  // left. u_L = 420 − 320 = 100, u_R = u_L − d = 75, d = 25: b(u_L+u_R)/(2d) = 0.1·175/50 = 0.35.
  // Left camera X = 0.4; the rig centre sits b/2 = 0.05 to its right: 0.4 − 0.05 = 0.35.
  const Eigen::Vector3d p = camera().backProjectDisparity(420, 180, 25.0);
  EXPECT_NEAR(p.x() - 0.1 / 2, 0.1 * (100 + 75) / (2 * 25.0), 1e-12);
}

TEST(StereoCamera, ProjectHandWorked) {
  Eigen::Vector2d uv;
  ASSERT_TRUE(camera().project({0.4, -0.25, 2.0}, &uv));
  EXPECT_NEAR(uv.x(), 420.0, 1e-12);  // 500·0.4/2 + 320
  EXPECT_NEAR(uv.y(), 180.0, 1e-12);  // 480·(−0.125) + 240
  EXPECT_FALSE(camera().project({0.1, 0.1, 0.0}, &uv));
  EXPECT_FALSE(camera().project({0.1, 0.1, -1.0}, &uv));
  EXPECT_FALSE(camera().project({NAN, 0.1, 1.0}, &uv));
}

TEST(StereoCamera, VisibilityRoundsToPixelCentres) {
  const StereoCamera c = camera();
  EXPECT_TRUE(c.isInImage({639.4, 0.0}));
  EXPECT_FALSE(c.isInImage({639.6, 0.0}));  // rounds to column 640
  EXPECT_TRUE(c.isInImage({-0.4, 10.0}));
  EXPECT_FALSE(c.isInImage({-0.6, 10.0}));
  EXPECT_TRUE(c.isInImage({23.6, 100.0}, 24));
  EXPECT_FALSE(c.isInImage({23.4, 100.0}, 24));
  EXPECT_FALSE(c.isInImage({100.0, 456.0}, 24));  // row 456 = 480 − 24 is cropped
}

TEST(StereoCamera, DepthErrorModelEq31) {
  // e_z = z²/(b·f)·e_d = 4 / (0.1·500) · 0.5 = 0.04 m
  EXPECT_NEAR(camera().depthError(2.0, 0.5), 0.04, 1e-12);
  // quadratic growth: doubling depth quadruples the error
  EXPECT_NEAR(camera().depthError(4.0, 0.5), 0.16, 1e-12);
}

TEST(StereoCamera, RejectsInvalidIntrinsics) {
  std::string error;
  EXPECT_FALSE(StereoCamera::create(640, 480, 0.0, 500, 320, 240, 0.1, &error));
  EXPECT_NE(error.find("focal"), std::string::npos) << error;
  EXPECT_FALSE(StereoCamera::create(640, 480, -500, 500, 320, 240, 0.1));
  EXPECT_FALSE(StereoCamera::create(640, 480, NAN, 500, 320, 240, 0.1));
  EXPECT_FALSE(StereoCamera::create(640, 480, 500, INFINITY, 320, 240, 0.1));
  EXPECT_FALSE(StereoCamera::create(640, 480, 500, 500, NAN, 240, 0.1));
  EXPECT_FALSE(StereoCamera::create(640, 480, 500, 500, 320, 240, 0.0, &error));
  EXPECT_NE(error.find("baseline"), std::string::npos) << error;
  EXPECT_FALSE(StereoCamera::create(640, 480, 500, 500, 320, 240, -0.1));
  EXPECT_FALSE(StereoCamera::create(0, 480, 500, 500, 320, 240, 0.1));
  EXPECT_FALSE(StereoCamera().valid());
  EXPECT_TRUE(camera().valid());
}

// A CameraInfo with fy = 1e-3 once stretched one frame over ±30 km; focal lengths are judged
// against the image (a 170° pinhole has f = 0.044 w) and against each other.
TEST(StereoCamera, RejectsImplausibleCalibrations) {
  std::string error;
  EXPECT_FALSE(StereoCamera::create(640, 480, 525, 1e-3, 320, 240, 0.1, &error));
  EXPECT_NE(error.find("focal lengths fx=525 fy=0.001 px are implausible for a 640x480 image (at "
                       "least 0.04 × 640 px"),
            std::string::npos)
      << error;
  EXPECT_FALSE(
      StereoCamera::create(640, 480, 25.5, 25.5, 320, 240, 0.1));  // below 0.04 × 640 = 25.6
  EXPECT_TRUE(StereoCamera::create(640, 480, 25.7, 25.7, 320, 240, 0.1));    // a 170° lens
  EXPECT_TRUE(StereoCamera::create(640, 480, 64000, 64000, 320, 240, 0.1));  // a telescope
  EXPECT_FALSE(StereoCamera::create(640, 480, 5000, 450, 320, 240, 0.1, &error));
  EXPECT_NE(error.find("fx / fy = 11.1"), std::string::npos) << error;
  EXPECT_TRUE(StereoCamera::create(640, 480, 500, 51, 320, 240, 0.1));
  // The principal point may lie outside the image (a crop) while every pixel's ray stays within
  // 85.4° of the optical axis: |u − cx| ≤ 12.5 · f = 12.5 · 525 = 6562.5 px.
  EXPECT_FALSE(StereoCamera::create(640, 480, 525, 525, 1e9, 240, 0.1, &error));
  EXPECT_NE(
      error.find(
          "principal point cx=1e+09 cy=240 px is implausible for a 640x480 image with fx=525"),
      std::string::npos)
      << error;
  EXPECT_TRUE(
      StereoCamera::create(640, 480, 525, 525, -5922, 240, 0.1));  // farthest pixel 6562 px away
  EXPECT_FALSE(StereoCamera::create(640, 480, 525, 525, -5923, 240, 0.1));  // 6563 px
  EXPECT_TRUE(StereoCamera::create(640, 480, 525, 525, 320, 6562, 0.1));
  EXPECT_FALSE(StereoCamera::create(640, 480, 525, 525, 320, 6563, 0.1));
  EXPECT_TRUE(StereoCamera::create(32, 32, 500, 500, -300, -300, 0.1));  // a crop 31–34° off axis
}
