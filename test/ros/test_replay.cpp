// A simulator bag played through launch/replay.launch (sim time) gives the same mesh as the
// offline pipeline on the same bag with the same parameters.
#include <stereo_fusion/GetFullMesh.h>

#include "RosTestSupport.h"

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/ros/BagSequence.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/RosParameters.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <stereo_msgs/DisparityImage.h>

using namespace stereo_fusion;


TEST(Replay, BagThroughTheNodeletEqualsTheOfflinePipeline) {
  ros::NodeHandle pnh("~");
  std::string bag_path;
  ASSERT_TRUE(pnh.getParam("bag", bag_path));
  std::string error;
  auto bag = BagSequence::open(bag_path, BagTopics{}, &error);
  ASSERT_TRUE(bag) << error;
  const long frames = static_cast<long>(bag->size());
  ASSERT_GT(frames, 5);

  test::DiagnosticsWatcher diagnostics;
  auto diag = [&](const char* key) { return diagnostics.value(key); };
  test::waitFor([&] { return diag("frames fused") >= frames; }, 120.0);
  ASSERT_EQ(diag("frames fused"), frames) << "dropped tf " << diag("dropped: tf timeout") << ", queue "
                                          << diag("dropped: queue full") << ", bad " << diag("dropped: bad input");

  // The same parameters as the nodelet, read the way the nodelet reads them.
  MapperConfig config;
  NodeConfig node;
  ASSERT_TRUE(loadParameters(ros::NodeHandle("/stereo_fusion"), &config, &node, &error)) << error;
  Mapper offline(config);
  for (size_t i = 0; i < bag->size(); ++i) {
    StereoFrame f;
    ASSERT_TRUE(bag->load(i, &f, &error)) << error;
    ASSERT_TRUE(offline.integrate(f).accepted);
  }

  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> live;
  ASSERT_TRUE(applyMeshUpdate(full.response.mesh, &live));
  const auto& expected = offline.mesh().submeshes();
  ASSERT_GT(expected.size(), 20u);
  test::expectSameSubmeshes(live, expected);
}

// At 50x the bag's rate (replay_fast.test) most frames are dropped somewhere: in rosbag's or the
// nodelet's subscriber queues (seen as gaps in header.seq), in the synchroniser or in the worker's
// queue. Frames in the bag = received + missed upstream; received = fused + every "dropped:".
TEST(ReplayFast, EveryFrameOfTheBagIsFusedOrCountedAsLost) {
  ros::NodeHandle pnh("~");
  std::string bag_path;
  ASSERT_TRUE(pnh.getParam("bag", bag_path));
  long frames = 0;
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(std::string("/stereo/disparity")))) {
      const auto disparity = m.instantiate<stereo_msgs::DisparityImage>();
      ASSERT_TRUE(disparity);
      ASSERT_EQ(disparity->header.seq, static_cast<uint32_t>(++frames)) << "the simulator numbers its frames";
    }
  }
  ASSERT_GT(frames, 100);

  test::DiagnosticsWatcher diagnostics;
  auto diag = [&](const std::string& key) { return std::max(0L, diagnostics.value(key)); };
  long received = 0, missed = 0, fused = 0, dropped = 0;
  auto read = [&] {
    received = diag("disparities received");
    missed = diag("disparities missed upstream (header.seq gaps)");
    fused = diag("frames fused");
    dropped = diagnostics.droppedTotal();
  };
  // The bag is played once the counters stop moving. Losses at its very end would leave no gap
  // behind them, so one more numbered disparity follows, alone (it finds no image: it is counted
  // as received and not synchronised).
  ros::NodeHandle nh;
  // Like rosbag play, a publisher without the header flag: roscpp keeps the seq set below
  // instead of numbering this publisher's messages from 0.
  ros::AdvertiseOptions options = ros::AdvertiseOptions::create<stereo_msgs::DisparityImage>(
      "/stereo/disparity", 1, ros::SubscriberStatusCallback(), ros::SubscriberStatusCallback(), ros::VoidConstPtr(),
      nullptr);
  options.has_header = false;
  ros::Publisher last_pub = nh.advertise(options);
  ASSERT_TRUE(test::waitFor([&] { return last_pub.getNumSubscribers() > 0; }, 30.0));
  long settled = -1;
  ASSERT_TRUE(test::waitFor([&] {
    read();
    const long now = received + missed;
    const bool still = now > 0 && now == settled;
    settled = now;
    if (!still) ros::WallDuration(2.0).sleep();
    return still;
  }, 120.0));
  stereo_msgs::DisparityImage last;
  last.header.seq = static_cast<uint32_t>(frames + 1);
  last.header.stamp = ros::Time::now() + ros::Duration(1.0);
  last_pub.publish(last);
  test::waitFor([&] { read(); return received + missed >= frames + 1 && fused + dropped >= received; }, 60.0);
  ros::WallDuration(2.0).sleep();
  ASSERT_TRUE(diagnostics.waitForNextReport(10.0));
  read();
  std::printf("[replay 50x] %ld frames in the bag + 1: %ld received, %ld missed upstream, %ld fused, %ld dropped\n",
              frames, received, missed, fused, dropped);
  EXPECT_EQ(received + missed, frames + 1);
  EXPECT_EQ(fused + dropped, received);
  EXPECT_GT(fused, 0);
}

int main(int argc, char** argv) { return test::runRosTests(argc, argv, "stereo_fusion_replay_test"); }
