// A stereo camera's image pair stream through image_proc + stereo_image_proc + stereo_fusion
// (launch/stereo_pipeline.launch; raw or, with rectified:=true, already rectified) gives a mesh of
// the simulated scene: every frame fused, many triangles, and the vertices on the scene's true
// surface.
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <stereo_fusion/GetFullMesh.h>

#include <algorithm>

#include "RosTestSupport.h"
#include "simulator/SceneLibrary.h"
#include "stereo_fusion/ros/MeshMessages.h"

using namespace stereo_fusion;

TEST(StereoPipeline, ImagePairsGiveAMeshOfTheScene) {
  ros::NodeHandle pnh("~");
  std::string bag_path, preset_name, right_image_topic;
  int seed = 0;
  ASSERT_TRUE(pnh.getParam("bag", bag_path));
  ASSERT_TRUE(pnh.getParam("right_image_topic", right_image_topic));
  ASSERT_TRUE(pnh.getParam("preset", preset_name));
  ASSERT_TRUE(pnh.getParam("seed", seed));
  long frames = 0;
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    rosbag::View right(bag, rosbag::TopicQuery(right_image_topic));
    rosbag::View disparity(bag, rosbag::TopicQuery("/stereo/disparity"));
    frames = static_cast<long>(right.size());
    ASSERT_EQ(disparity.size(), 0u) << "the bag must hold image pairs only";
  }
  ASSERT_GE(frames, 5);

  test::DiagnosticsWatcher diagnostics;
  auto diag = [&](const char* key) { return diagnostics.value(key); };
  test::waitFor([&] { return diag("frames fused") >= frames; }, 120.0);
  EXPECT_EQ(diag("frames fused"), frames)
      << "dropped tf " << diag("dropped: tf timeout") << ", queue " << diag("dropped: queue full")
      << ", bad " << diag("dropped: bad input");
  ASSERT_GT(diag("frames fused"), 0);

  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> mesh;
  ASSERT_TRUE(applyMeshUpdate(full.response.mesh, &mesh));
  size_t triangles = 0;
  // Judged on the table and what stands on it (within 1 m of the table centre, 1 m from the
  // camera): the room's walls are 2-4 m away, where 1/16 px of disparity is already 2-6 cm.
  std::vector<double> distances_m;
  const auto preset = sim::makePreset(preset_name, static_cast<uint32_t>(seed));
  ASSERT_TRUE(preset);
  for (const auto& [key, sub] : mesh) {
    triangles += sub.triangles.size();
    for (const auto& p : sub.positions)
      if (Eigen::Vector3d(p.x(), p.y(), p.z() - 0.75).norm() < 1.0)
        distances_m.push_back(preset->scene.distanceToSurface(p.cast<double>()));
  }
  std::sort(distances_m.begin(), distances_m.end());
  ASSERT_FALSE(distances_m.empty());
  const double median_m = distances_m[distances_m.size() / 2];
  const double p90_m = distances_m[distances_m.size() * 9 / 10];
  for (int q = 1; q < 10; ++q)
    std::printf("p%d %.4f ", q * 10, distances_m[distances_m.size() * q / 10]);
  std::printf(" (%zu vertices near the table)\n", distances_m.size());
  RecordProperty("triangles", static_cast<int>(triangles));
  std::printf(
      "[pipeline] %ld frames fused, %zu blocks, %zu triangles; |distance to scene| median %.4f m, "
      "p90 %.4f m\n",
      diag("frames fused"), mesh.size(), triangles, median_m, p90_m);
  EXPECT_GT(triangles, 3000u);
  EXPECT_GT(distances_m.size(), 5000u);
  // 2 cm voxels; stereo_image_proc's SGBM disparity at 1/16 px.
  EXPECT_LT(median_m, 0.01);
  EXPECT_LT(p90_m, 0.03);
}

int main(int argc, char** argv) {
  return test::runRosTests(argc, argv, "stereo_fusion_pipeline_test");
}
