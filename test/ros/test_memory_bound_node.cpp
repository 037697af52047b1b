// The memory bound through the real nodelet: the block budget holds, evictions are counted on
// /diagnostics, and a subscriber applying ~mesh_update (changed blocks + removed_keys) ends
// with exactly the mesh ~get_full_mesh returns.
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/MeshUpdate.h>
#include <tf2_ros/transform_broadcaster.h>

#include <mutex>

#include "../unit/TestSupport.h"
#include "RosTestSupport.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/MessageConversions.h"

using namespace stereo_fusion;

TEST(MemoryBoundNode, BudgetHoldsAndTheStreamedMeshFollowsEvictions) {
  ros::NodeHandle nh;
  ros::Publisher disparity_pub = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 10);
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 10);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 10);
  std::mutex mutex;
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> streamed;
  size_t removed_keys = 0;
  uint64_t last_sequence = 0;
  int gaps = 0;
  bool applied_ok = true;
  ros::Subscriber sub = nh.subscribe<MeshUpdate>(
      "/stereo_fusion/mesh_update", 100, [&](const MeshUpdate::ConstPtr& u) {
        std::lock_guard<std::mutex> lock(mutex);
        if (last_sequence && u->sequence != last_sequence + 1) ++gaps;
        last_sequence = u->sequence;
        removed_keys += u->removed_keys.size() / 3;
        applied_ok &= applyMeshUpdate(*u, &streamed);
      });
  test::DiagnosticsWatcher diagnostics;
  auto diag = [&](const char* key) { return diagnostics.value(key); };
  tf2_ros::TransformBroadcaster tf;
  ASSERT_TRUE(test::waitFor(
      [&] {
        return disparity_pub.getNumSubscribers() > 0 && image_pub.getNumSubscribers() > 0 &&
               info_pub.getNumSubscribers() > 0 && sub.getNumPublishers() > 0;
      },
      30.0));
  ASSERT_TRUE(test::waitForTfSubscriber(30.0)) << "the nodelet's tf listener did not connect";

  // A corridor: floor 0.5 m below, wall 2 m ahead; the camera slides 30 cm along it per frame.
  sim::AnalyticScene corridor;
  corridor.add(sim::makePlane({0, 0.5, 0}, {0, -1, 0}), {180, 160, 120});
  corridor.add(sim::makePlane({0, 0, 2.0}, {0, 0, -1}), {90, 120, 200});
  const StereoCamera camera = *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1);
  const int frames = 20;
  for (int k = 0; k < frames; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().x() = 0.3 * k;
    const StereoFrame frame = test::renderFrame(corridor, camera, T);
    const test::FrameMessages m = test::frameMessages(frame, &tf);
    ros::WallDuration(0.05).sleep();
    disparity_pub.publish(m.disparity);
    image_pub.publish(m.image);
    info_pub.publish(m.info);
    // One at a time, so the budget is checked after every frame.
    ASSERT_TRUE(test::waitFor([&] { return diag("frames fused") >= k + 1; }, 30.0))
        << "frame " << k;
    EXPECT_LE(diag("blocks"), 300) << "after frame " << k;
  }
  ros::WallDuration(1.5).sleep();  // diagnostics (1 Hz) and the last update
  EXPECT_LE(diag("blocks"), 300);
  EXPECT_GT(diag("blocks evicted"), 100);
  EXPECT_EQ(diag("dropped: bad input"), 0);

  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> reference;
  ASSERT_TRUE(applyMeshUpdate(full.response.mesh, &reference));
  ASSERT_GT(reference.size(), 20u);
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_TRUE(applied_ok);
  EXPECT_EQ(gaps, 0);
  EXPECT_GT(removed_keys, 10u) << "evicted blocks must reach subscribers as removed_keys";
  EXPECT_EQ(full.response.mesh.sequence, last_sequence);
  test::expectSameSubmeshes(streamed, reference);
}

int main(int argc, char** argv) {
  return test::runRosTests(argc, argv, "stereo_fusion_memory_bound_test");
}
