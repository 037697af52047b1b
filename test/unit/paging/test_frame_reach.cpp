// FrameReach: every block a frame changes, and every block within one block of it (what the
// mesher reads around a change), passes; blocks behind the camera or beyond its reach do not.
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
    const double far_m = config.max_depth_m + config.truncationBand().maxM();
    const FrameReach reach(frame, far_m, config.blockSizeM());
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
  const double block_m = 0.16;
  const FrameReach reach(frame, 4.0, block_m);
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
}
