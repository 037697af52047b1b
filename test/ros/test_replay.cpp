// A simulator bag played through launch/replay.launch (sim time) gives the same mesh as the
// offline pipeline on the same bag with the same parameters.
#include <stereo_fusion/GetFullMesh.h>

#include "RosTestSupport.h"

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/ros/BagSequence.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/RosParameters.h"

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

int main(int argc, char** argv) { return test::runRosTests(argc, argv, "stereo_fusion_replay_test"); }
