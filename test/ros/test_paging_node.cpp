// Paging through the real nodelet (max_map_memory_mb): a camera walks a corridor and back, the
// map pages out and in, /diagnostics counts it with no paging error, and a subscriber applying
// ~mesh_update ends with exactly the mesh ~get_full_mesh returns — paged-out blocks included.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/MeshUpdate.h>
#include <tf2_ros/transform_broadcaster.h>

#include <mutex>

#include "../unit/TestSupport.h"
#include "RosTestSupport.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/MessageConversions.h"

using namespace stereo_fusion;

TEST(PagingNode, AWalkThereAndBackPagesOutAndInAndTheStreamedMeshIsWhole) {
  ros::NodeHandle nh;
  ros::Publisher disparity_pub = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 10);
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 10);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 10);
  std::mutex mutex;
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> streamed;
  bool applied_ok = true;
  uint64_t last_sequence = 0;
  ros::Subscriber sub = nh.subscribe<MeshUpdate>("/stereo_fusion/mesh_update", 100,
                                                 [&](const MeshUpdate::ConstPtr& u) {
                                                   std::lock_guard<std::mutex> lock(mutex);
                                                   last_sequence = u->sequence;
                                                   applied_ok &= applyMeshUpdate(*u, &streamed);
                                                 });
  // Paging's own ERRORs ("paging: ..."); the level alone would also turn ERROR for stale input
  // once the frames stop (input_timeout_s).
  std::string paging_error;
  ros::Subscriber levels = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& a) {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& s : a->status)
          if (s.name.find(": fusion") != std::string::npos &&
              s.level == diagnostic_msgs::DiagnosticStatus::ERROR &&
              s.message.rfind("paging", 0) == 0)
            paging_error = s.message;
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

  // A corridor: floor 0.5 m below, wall 2 m ahead; the camera slides 30 cm a frame along it,
  // then back to the start, where the first blocks come back from the store.
  sim::AnalyticScene corridor;
  corridor.add(sim::makePlane({0, 0.5, 0}, {0, -1, 0}), {180, 160, 120});
  corridor.add(sim::makePlane({0, 0, 2.0}, {0, 0, -1}), {90, 120, 200});
  corridor.add(sim::makeSphere({1.5, 0.2, 1.6}, 0.25), {200, 60, 60});
  const StereoCamera camera = *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1);
  const int frames = 30;
  for (int k = 0; k < frames; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().x() = 0.3 * (k < frames / 2 ? k : frames - 1 - k);
    const StereoFrame frame = test::renderFrame(corridor, camera, T);
    const test::FrameMessages m = test::frameMessages(frame, &tf);
    ros::WallDuration(0.05).sleep();
    disparity_pub.publish(m.disparity);
    image_pub.publish(m.image);
    info_pub.publish(m.info);
    ASSERT_TRUE(test::waitFor([&] { return diag("frames fused") >= k + 1; }, 30.0))
        << "frame " << k;
  }
  ros::WallDuration(1.5).sleep();  // diagnostics (1 Hz) and the last update
  EXPECT_GT(diag("paging: blocks paged out"), 100);
  EXPECT_GT(diag("paging: blocks paged in"), 10) << "the walk back reads the first blocks back";
  EXPECT_GT(diag("paging: blocks in the store"), 0);
  EXPECT_EQ(diag("paging: pages unreadable (blocks lost)"), 0);
  EXPECT_EQ(diag("dropped: bad input"), 0);

  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> reference;
  ASSERT_TRUE(applyMeshUpdate(full.response.mesh, &reference));
  std::lock_guard<std::mutex> lock(mutex);
  // The full mesh holds the paged-out blocks' submeshes too: the corridor's first metres.
  bool has_start = false;
  for (const auto& [key, sub] : reference) has_start = has_start || key.x * 0.32 < 0.3;
  EXPECT_TRUE(has_start);
  EXPECT_TRUE(applied_ok);
  EXPECT_EQ(full.response.mesh.sequence, last_sequence);
  test::expectSameSubmeshes(streamed, reference);
  EXPECT_TRUE(paging_error.empty()) << paging_error;
}

int main(int argc, char** argv) {
  return test::runRosTests(argc, argv, "stereo_fusion_paging_test");
}
