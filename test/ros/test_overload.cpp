// Input much faster than fusion: the queue stays bounded, every frame is fused or counted as
// dropped, the node keeps running. "Faster" does not depend on the machine's speed: the
// frames' tf comes only after the last frame, so the worker waits on the first frame's tf
// (overload.test: tf_timeout_s 10 s) while the rest arrive at a queue of 2.
#include <tf2_ros/transform_broadcaster.h>

#include <cstdio>

#include "RosTestSupport.h"

#include "../unit/TestSupport.h"
#include "stereo_fusion/ros/MessageConversions.h"

using namespace stereo_fusion;


TEST(Overload, QueueStaysBoundedAndEveryFrameIsCounted) {
  ros::NodeHandle nh;
  ros::Publisher disparity_pub = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 100);
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 100);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 100);
  test::DiagnosticsWatcher diagnostics;
  auto diag = [&](const std::string& key) { return diagnostics.value(key); };
  tf2_ros::TransformBroadcaster tf;
  auto connected = [&] {
    return disparity_pub.getNumSubscribers() > 0 && image_pub.getNumSubscribers() > 0 && info_pub.getNumSubscribers() > 0;
  };
  for (int i = 0; i < 300 && !connected(); ++i) ros::WallDuration(0.1).sleep();
  ASSERT_TRUE(connected());
  ASSERT_TRUE(test::waitForTfSubscriber(30.0)) << "the nodelet's tf listener did not connect";

  // 640×480 frames published back to back, their tf held back until all are sent.
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0.4, 0}, {0, -1, 0}));
  scene.add(sim::makeSphere({0, 0, 1.5}, 0.3));
  const StereoFrame frame = test::renderFrame(scene, test::vgaCamera(), Eigen::Isometry3d::Identity());
  const int sent = 40;
  std::vector<std_msgs::Header> headers;
  for (int k = 0; k < sent; ++k) {
    const test::FrameMessages m = test::frameMessages(frame, nullptr);
    headers.push_back(m.header);
    disparity_pub.publish(m.disparity);
    image_pub.publish(m.image);
    info_pub.publish(m.info);
    ros::WallDuration(0.01).sleep();
  }
  for (const std_msgs::Header& header : headers) tf.sendTransform(toTransform(frame.T_world_camera, "world", header));
  // Every disparity that reached the node is fused or in exactly one "dropped:" counter.
  auto accounted = [&] {
    long sum = diag("frames fused");
    for (const std::string& key : diagnostics.keys())
      if (key.rfind("dropped: ", 0) == 0) sum += std::max(0L, diag(key));
    return sum;
  };
  test::waitFor([&] { return diag("disparities received") > 0 && accounted() >= diag("disparities received"); }, 120.0);
  ros::WallDuration(1.5).sleep();  // a last diagnostics update
  const long received = diag("frames received"), disparities = diag("disparities received");
  std::printf("[overload] %ld disparities received, %ld frames matched, %ld fused, %ld dropped as the queue was full\n",
              disparities, received, diag("frames fused"), diag("dropped: queue full"));
  EXPECT_GT(received, sent / 2) << "the synchroniser matched too few frames";
  EXPECT_LE(disparities, sent);
  EXPECT_EQ(accounted(), disparities) << "every disparity received is fused or counted as dropped";
  EXPECT_GT(diag("dropped: queue full"), 0) << "with queue_size 2 some frames must be dropped";
  EXPECT_GT(diag("frames fused"), 1);
  EXPECT_EQ(diag("dropped: bad input"), 0);
}

int main(int argc, char** argv) { return test::runRosTests(argc, argv, "stereo_fusion_overload_test"); }
