// A simulator bag played through launch/replay.launch (sim time) gives the same mesh as the
// offline pipeline on the same bag with the same parameters.
#include <gtest/gtest.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>
#include <stereo_fusion/GetFullMesh.h>

#include <map>
#include <mutex>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/ros/BagSequence.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/RosParameters.h"

using namespace stereo_fusion;

namespace {
std::mutex g_mutex;
std::map<std::string, std::string> g_diagnostics;

void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& a) {
  std::lock_guard<std::mutex> lock(g_mutex);
  for (const auto& status : a->status)
    if (status.name.find("fusion") != std::string::npos)
      for (const auto& kv : status.values) g_diagnostics[kv.key] = kv.value;
}

long diag(const std::string& key) {
  std::lock_guard<std::mutex> lock(g_mutex);
  auto it = g_diagnostics.find(key);
  return it == g_diagnostics.end() ? -1 : std::stol(it->second);
}
}  // namespace

TEST(Replay, BagThroughTheNodeletEqualsTheOfflinePipeline) {
  ros::NodeHandle pnh("~");
  std::string bag_path;
  ASSERT_TRUE(pnh.getParam("bag", bag_path));
  std::string error;
  auto bag = BagSequence::open(bag_path, BagTopics{}, &error);
  ASSERT_TRUE(bag) << error;
  const long frames = static_cast<long>(bag->size());
  ASSERT_GT(frames, 5);

  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe("/diagnostics", 10, onDiagnostics);
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(120.0);
  while (ros::ok() && ros::WallTime::now() < end && diag("frames fused") < frames) ros::WallDuration(0.2).sleep();
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
  ASSERT_EQ(live.size(), expected.size());
  for (const auto& [key, sub] : expected) {
    auto it = live.find(key);
    ASSERT_NE(it, live.end()) << key;
    EXPECT_EQ(it->second.positions, sub.positions) << key;
    EXPECT_EQ(it->second.triangles, sub.triangles) << key;
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "stereo_fusion_replay_test");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
