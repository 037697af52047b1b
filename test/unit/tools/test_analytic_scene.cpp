// The test ground truth itself must be right.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "TestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

TEST(AnalyticScene, RaycastsHitTheSurface) {
  const Eigen::Vector3d o(0.01, -0.02, -1.0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.rotate(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  pose.translation() = Eigen::Vector3d(0.1, 0.2, 1.0);
  std::vector<std::unique_ptr<sim::Primitive>> prims;
  prims.push_back(sim::makeSphere({0, 0, 1}, 0.3));
  prims.push_back(sim::makePlane({0, 0, 2}, {0, 0, -1}));
  prims.push_back(sim::makeBox(pose, {0.2, 0.1, 0.3}));
  prims.push_back(sim::makeTorus(pose, 0.3, 0.1));
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> d(-0.25, 0.25);
  for (const auto& p : prims) {
    int hits = 0;
    for (int n = 0; n < 500; ++n) {
      const Eigen::Vector3d dir = Eigen::Vector3d(d(rng), d(rng), 1.0).normalized();
      const double t = p->raycast(o, dir, 1e-9);
      if (!std::isfinite(t)) continue;
      ++hits;
      EXPECT_NEAR(p->signedDistance(o + t * dir), 0.0, 1e-7);
      // Nothing nearer along the ray is inside the solid.
      for (double s = 0.01; s < t - 1e-3; s += 0.01)
        EXPECT_GT(p->signedDistance(o + s * dir), -1e-9);
    }
    EXPECT_GT(hits, 50);
  }
  EXPECT_NEAR(prims[0]->signedDistance({0, 0, 1.5}), 0.2, 1e-12);
  EXPECT_NEAR(prims[1]->signedDistance({5, 3, 1.5}), 0.5, 1e-12);  // on the normal's side
}

TEST(AnalyticScene, RenderedDisparityMatchesTheCameraModel) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 2.0}, {0, 0, -1}));
  cv::Mat depth, color;
  const StereoCamera camera = vgaCamera();
  sim::renderDepthAndColor(scene, camera, Eigen::Isometry3d::Identity(), &depth, &color);
  EXPECT_NEAR(depth.at<float>(0, 0), 2.0f, 1e-5f);
  EXPECT_NEAR(depth.at<float>(479, 639), 2.0f, 1e-5f);
  const cv::Mat disparity = sim::disparityFromDepth(depth, camera);
  EXPECT_NEAR(disparity.at<float>(100, 100), 525 * 0.1 / 2.0, 1e-4);
  // Texture is not flat (stereo matching needs it).
  cv::Scalar mean, stddev;
  cv::meanStdDev(color, mean, stddev);
  EXPECT_GT(stddev[0], 10.0);
}

TEST(AnalyticScene, LookAtIsARightHandedOpticalFrame) {
  const Eigen::Isometry3d T = sim::lookAt({1, 2, 3}, {1, 2, 5}, -Eigen::Vector3d::UnitY());
  EXPECT_NEAR((T.linear().col(2) - Eigen::Vector3d::UnitZ()).norm(), 0, 1e-12);
  EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-12);
  EXPECT_NEAR((T * Eigen::Vector3d(0, 0, 2) - Eigen::Vector3d(1, 2, 5)).norm(), 0, 1e-12);
}
