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
  ros::Publisher disparity_pub =
      nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 100);
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 100);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 100);
  test::DiagnosticsWatcher diagnostics;
  auto diag = [&](const std::string& key) { return diagnostics.value(key); };
  tf2_ros::TransformBroadcaster tf;
  auto connected = [&] {
    return disparity_pub.getNumSubscribers() > 0 && image_pub.getNumSubscribers() > 0 &&
           info_pub.getNumSubscribers() > 0;
  };
  for (int i = 0; i < 300 && !connected(); ++i) ros::WallDuration(0.1).sleep();
  ASSERT_TRUE(connected());
  ASSERT_TRUE(test::waitForTfSubscriber(30.0)) << "the nodelet's tf listener did not connect";

  // 640×480 frames published back to back, their tf held back until all are sent.
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0.4, 0}, {0, -1, 0}));
  scene.add(sim::makeSphere({0, 0, 1.5}, 0.3));
  const StereoFrame frame =
      test::renderFrame(scene, test::vgaCamera(), Eigen::Isometry3d::Identity());
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
  for (const std_msgs::Header& header : headers)
    tf.sendTransform(toTransform(frame.T_world_camera, "map", header));
  // Every disparity that reached the node is fused or in exactly one "dropped:" counter.
  auto accounted = [&] { return diag("frames fused") + diagnostics.droppedTotal(); };
  test::waitFor(
      [&] {
        return diag("disparities received") > 0 && accounted() >= diag("disparities received");
      },
      120.0);
  ros::WallDuration(1.5).sleep();  // a last diagnostics update
  const long received = diag("frames received"), disparities = diag("disparities received");
  std::printf(
      "[overload] %ld disparities received, %ld frames matched, %ld fused, %ld dropped as the "
      "queue was full\n",
      disparities, received, diag("frames fused"), diag("dropped: queue full"));
  EXPECT_GT(received, sent / 2) << "the synchroniser matched too few frames";
  EXPECT_LE(disparities, sent);
  EXPECT_EQ(accounted(), disparities) << "every disparity received is fused or counted as dropped";
  EXPECT_GT(diag("dropped: queue full"), 0) << "with queue_size 2 some frames must be dropped";
  EXPECT_GT(diag("frames fused"), 1);
  EXPECT_EQ(diag("dropped: bad input"), 0);
}

// A burst of numbered frames published back to back, faster than the transport delivers them:
// whatever the publisher's queue, the subscriber's queue or the synchroniser discards is still
// counted. Sent = received + missed upstream (header.seq gaps); received = fused + dropped.
TEST(Overload, ABurstOfNumberedFramesIsAccountedForFrameByFrame) {
  ros::NodeHandle nh;
  // Small outgoing queues: the publishers must discard some frames of the burst.
  ros::Publisher disparity_pub = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 8);
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 8);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 8);
  test::DiagnosticsWatcher diagnostics;
  auto diag = [&](const std::string& key) { return std::max(0L, diagnostics.value(key)); };
  auto connected = [&] {
    return disparity_pub.getNumSubscribers() > 0 && image_pub.getNumSubscribers() > 0 &&
           info_pub.getNumSubscribers() > 0;
  };
  ASSERT_TRUE(test::waitFor(connected, 30.0));
  // The broadcaster first: waitForTfSubscriber() waits on the /tf publication it shares. Created
  // after, it would advertise /tf anew and the burst's transforms could go out before the
  // nodelet reconnected (seen once: every frame of the burst dropped for want of tf).
  tf2_ros::TransformBroadcaster tf;
  ASSERT_TRUE(test::waitForTfSubscriber(30.0));
  auto dropped = [&] { return diagnostics.droppedTotal(); };
  const std::string kReceived = "disparities received",
                    kMissed = "disparities missed upstream (header.seq gaps)";

  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0.4, 0}, {0, -1, 0}));
  const StereoCamera camera = *StereoCamera::create(160, 120, 131.25, 131.25, 79.5, 59.5, 0.1);
  const StereoFrame frame = test::renderFrame(scene, camera, Eigen::Isometry3d::Identity());
  const int sent = 600;
  const ros::Time t0 = ros::Time::now() + ros::Duration(1.0);
  std::vector<test::FrameMessages> messages;
  // roscpp numbers each publisher's messages (header.seq 0, 1, 2, …) as it sends them.
  for (int k = 0; k <= sent + 1; ++k)  // the primer, the burst, a last frame after it
    messages.push_back(
        test::frameMessages(frame, &tf, "left_optical", t0 + ros::Duration(0.001 * k)));
  ros::WallDuration(0.5).sleep();  // the transforms reach the nodelet's buffer before the frames
  auto publish = [&](const test::FrameMessages& m) {
    disparity_pub.publish(m.disparity);
    image_pub.publish(m.image);
    info_pub.publish(m.info);
  };
  // A full queue discards its OLDEST message, so a burst loses its first frames: they are seen
  // missing only after a numbered frame that arrived (as on a robot, whose stream runs before the
  // burst). That frame goes first, alone.
  ASSERT_TRUE(diagnostics.waitForNextReport(10.0));
  const long before_primer = diag(kReceived);
  publish(messages.front());
  ASSERT_TRUE(test::waitFor([&] { return diag(kReceived) > before_primer; }, 30.0));
  ASSERT_TRUE(
      test::waitFor([&] { return diag("frames fused") + dropped() >= diag(kReceived); }, 30.0));
  ASSERT_TRUE(diagnostics.waitForNextReport(10.0));
  const long received0 = diag(kReceived), missed0 = diag(kMissed), fused0 = diag("frames fused"),
             dropped0 = dropped();
  for (int k = 1; k <= sent; ++k) publish(messages[k]);
  // One more frame after a pause: whatever the burst lost at its end shows as a gap before it.
  ros::WallDuration(1.0).sleep();
  publish(messages.back());
  const int numbered = sent + 1;
  long received = 0, missed = 0, fused = 0, lost = 0;
  auto read = [&] {
    received = diag(kReceived) - received0;
    missed = diag(kMissed) - missed0;
    fused = diag("frames fused") - fused0;
    lost = dropped() - dropped0;
  };
  // The last frame, sent alone after a pause, arrives: every gap before it is seen.
  test::waitFor(
      [&] {
        read();
        return received + missed >= numbered && fused + lost >= received;
      },
      120.0);
  ros::WallDuration(2.0).sleep();  // nothing more may arrive
  ASSERT_TRUE(diagnostics.waitForNextReport(10.0));
  read();
  std::printf("[overload] burst of %d: %ld received, %ld missed upstream, %ld fused, %ld dropped\n",
              sent, received, missed, fused, lost);
  EXPECT_EQ(received + missed, numbered) << "every frame sent was received or seen missing";
  EXPECT_EQ(fused + lost, received) << "every frame received was fused or dropped with a reason";
  EXPECT_GT(fused, 0);
}

int main(int argc, char** argv) {
  return test::runRosTests(argc, argv, "stereo_fusion_overload_test");
}
