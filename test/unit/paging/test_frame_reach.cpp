// FrameReach: every block a frame changes, and every block within one block of it (what the
// mesher reads around a change), passes; blocks behind the camera, beyond what its pixels
// measure (a wall) or beyond max_depth_m do not.
#include <gtest/gtest.h>

#include "MeshTestSupport.h"
#include "stereo_fusion/paging/FrameReach.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

TEST(FrameReach, EveryBlockAFrameChangesAndItsNeighboursPass) {
  const sim::AnalyticScene scene = floorAndSphere();
  MapperConfig config;
  config.voxel_size_m = 0.02;
  for (int view = 0; view < 4; ++view) {
    Mapper mapper(config);
    const StereoFrame frame = renderFrame(scene, qvgaCamera(), floorAndSphereView(3 * view));
    const IntegrationResult r = mapper.integrate(frame);
    ASSERT_TRUE(r.accepted) << r.error;
    ASSERT_GT(r.updated_blocks.size(), 100u);
    const FrameReach reach(frame, config.max_depth_m, config.truncationBand().maxM(), 0.0,
                           config.blockSizeM());
    for (const BlockKey& key : r.updated_blocks)
      for (int d = 0; d < 27; ++d) {
        const BlockKey near = key.offset(d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1);
        const Eigen::Vector3d lo(near.x, near.y, near.z);
        EXPECT_TRUE(reach.mayReach(lo, lo + Eigen::Vector3d::Ones())) << near;
      }
  }
}

TEST(FrameReach, BlocksBehindTheCameraOrBeyondItsReachFail) {
  StereoFrame frame;
  frame.camera = qvgaCamera();  // at the origin, looking along +z
  // Every pixel measures 3.5 m; with a band of 0.5 m the frame reaches 4 m.
  frame.disparity_px =
      cv::Mat(240, 320, CV_32FC1, cv::Scalar(frame.camera.disparityFromDepth(3.5)));
  const double block_m = 0.16;
  const FrameReach reach(frame, 6.0, 0.5, 0.0, block_m);
  EXPECT_NEAR(reach.farM(), 4.0, 1e-9);
  auto reaches = [&](const Eigen::Vector3d& p_m) {
    const Eigen::Vector3d lo = (p_m / block_m).array().floor();
    return reach.mayReach(lo, lo + Eigen::Vector3d::Ones());
  };
  EXPECT_TRUE(reaches({0, 0, 2.0}));
  EXPECT_TRUE(reaches({0, 0, 4.1})) << "within one block of the far plane";
  EXPECT_FALSE(reaches({0, 0, 4.5}));
  EXPECT_FALSE(reaches({0, 0, -0.5}));
  EXPECT_TRUE(reaches({0, 0, -0.1})) << "the block around the camera and its neighbours";
  // The image is 320 px wide at f = 262.5: at 2 m depth its edge lies at x ≈ ±1.22 m.
  EXPECT_TRUE(reaches({1.3, 0, 2.0}));
  EXPECT_FALSE(reaches({1.8, 0, 2.0}));
  EXPECT_FALSE(reaches({-1.8, 0, 2.0}));
  // max_depth_m caps what a pixel reaches.
  const FrameReach capped(frame, 2.0, 0.5, 0.0, block_m);
  EXPECT_NEAR(capped.farM(), 2.5, 1e-9);
}

TEST(FrameReach, AWallStopsTheReachWhereItsPixelsMeasureIt) {
  // The right half of the image sees a wall at 1 m, the left half measures 5 m, the top rows
  // nothing at all.
  StereoFrame frame;
  frame.camera = qvgaCamera();
  frame.disparity_px = cv::Mat(240, 320, CV_32FC1, cv::Scalar(0.0f));
  const float near_d = static_cast<float>(frame.camera.disparityFromDepth(1.0));
  const float far_d = static_cast<float>(frame.camera.disparityFromDepth(5.0));
  frame.disparity_px(cv::Rect(0, 64, 160, 176)).setTo(far_d);
  frame.disparity_px(cv::Rect(160, 64, 160, 176)).setTo(near_d);
  const double block_m = 0.08;
  const FrameReach reach(frame, 8.0, 0.1, 0.0, block_m);
  const StereoCamera& c = frame.camera;
  auto reaches = [&](double u, double v, double z) {
    const Eigen::Vector3d p = c.backProject(u, v, z);
    const Eigen::Vector3d lo = (p / block_m).array().floor();
    return reach.mayReach(lo, lo + Eigen::Vector3d::Ones());
  };
  EXPECT_TRUE(reaches(80, 150, 4.5)) << "in front of the far surface";
  EXPECT_TRUE(reaches(250, 150, 1.0)) << "at the wall";
  EXPECT_FALSE(reaches(250, 150, 3.0)) << "behind the wall";
  EXPECT_FALSE(reaches(250, 150, 6.0));
  EXPECT_FALSE(reaches(80, 20, 3.0)) << "pixels without a match reach nothing";
  // free_space_unmeasured_range_m: unmatched pixels count as seeing free space that far.
  const FrameReach unmeasured(frame, 8.0, 0.1, 4.0, block_m);
  const Eigen::Vector3d p = c.backProject(80, 20, 3.0);
  const Eigen::Vector3d lo = (p / block_m).array().floor();
  EXPECT_TRUE(unmeasured.mayReach(lo, lo + Eigen::Vector3d::Ones()));
}
