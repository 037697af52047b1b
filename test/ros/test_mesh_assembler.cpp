// A base-station MeshAssembler that joins mid-run (loaded into a running nodelet manager after
// half of the frames were fused) ends with exactly the robot's mesh, and with the mesh an offline
// Mapper builds from the same frames (within the stated quantisation step when the robot sends
// the compact encoding). Its ~save_mesh writes the same PLY as the robot's.
#include <nodelet/NodeletLoad.h>
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/SaveMesh.h>
#include <tf2_ros/transform_broadcaster.h>
#include <unistd.h>

#include <fstream>
#include <iterator>

#include "../unit/TestSupport.h"
#include "RosTestSupport.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/MessageConversions.h"
#include "stereo_fusion/ros/RosParameters.h"

using namespace stereo_fusion;

namespace {

using SubmeshMap = std::unordered_map<BlockKey, SubMesh, BlockKeyHash>;

sim::AnalyticScene scene() {
  sim::AnalyticScene s;
  s.add(sim::makePlane({0, 0.3, 0}, {0, -1, 0}), {180, 160, 120});
  s.add(sim::makeSphere({0.05, 0.1, 1.2}, 0.2), {200, 60, 60});
  s.add(sim::makeBox(Eigen::Isometry3d(Eigen::Translation3d(-0.35, 0.15, 1.0)), {0.1, 0.15, 0.1}), {60, 160, 60});
  return s;
}

/// The mesh a service returns, decoded; its sequence in `sequence`.
bool fetch(const std::string& service, SubmeshMap* mesh, uint64_t* sequence) {
  GetFullMesh srv;
  if (!ros::service::call(service, srv)) return false;
  mesh->clear();
  *sequence = srv.response.mesh.sequence;
  return applyMeshUpdate(srv.response.mesh, mesh);
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

TEST(MeshAssembler, JoinedMidRunEndsWithExactlyTheRobotsMesh) {
  ros::NodeHandle nh;
  std::string encoding_name;
  ASSERT_TRUE(nh.getParam("/stereo_fusion/mesh_encoding", encoding_name));
  const bool compact = encoding_name == "compact";
  auto disparity_pub = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 20);
  auto image_pub = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 20);
  auto info_pub = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 20);
  tf2_ros::TransformBroadcaster tf;
  test::DiagnosticsWatcher diagnostics;
  ASSERT_TRUE(test::waitFor([&] {
    return disparity_pub.getNumSubscribers() > 0 && image_pub.getNumSubscribers() > 0 && info_pub.getNumSubscribers() > 0;
  }, 30.0)) << "the fusion nodelet did not connect";

  MapperConfig config;
  NodeConfig node;
  std::string error;
  ASSERT_TRUE(loadParameters(ros::NodeHandle("/stereo_fusion"), &config, &node, &error)) << error;
  Mapper offline(config);

  const sim::AnalyticScene s = scene();
  const StereoCamera camera = *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1);
  const int kFrames = 10;
  auto publishFrame = [&](int f) {
    const double angle = -0.5 + 0.1 * f;
    const Eigen::Vector3d eye(0.05 + 1.0 * std::sin(angle), -0.25, 1.2 - 1.0 * std::cos(angle));
    const StereoFrame frame = test::renderFrame(s, camera, sim::lookAt(eye, {0.0, 0.1, 1.1}, -Eigen::Vector3d::UnitY()));
    std_msgs::Header header;
    header.stamp = ros::Time::now();
    header.frame_id = "left_optical";
    tf.sendTransform(toTransform(frame.T_world_camera, "world", header));
    stereo_msgs::DisparityImage d;
    sensor_msgs::Image i;
    sensor_msgs::CameraInfo c;
    toMessages(frame, header, 128.0f, &d, &i, &c);
    // The offline reference sees exactly what the nodelet sees: the messages, converted back.
    StereoFrame received;
    ASSERT_TRUE(toStereoFrame(d, i, c, frame.T_world_camera, &received, &error)) << error;
    ASSERT_TRUE(offline.integrate(received).accepted);
    ros::WallDuration(0.05).sleep();  // tf first, as a SLAM stack running ahead would
    disparity_pub.publish(d);
    image_pub.publish(i);
    info_pub.publish(c);
  };

  // First half: nobody at the base station yet.
  for (int f = 0; f < kFrames / 2; ++f) publishFrame(f);
  ASSERT_TRUE(test::waitFor([&] { return diagnostics.value("frames fused") >= kFrames / 2; }, 60.0));

  // The base station joins: MeshAssembler loaded into the running manager, remapped to the robot.
  nodelet::NodeletLoad load;
  load.request.name = "/mesh_assembler";
  load.request.type = "stereo_fusion/MeshAssembler";
  load.request.remap_source_args = {"/mesh_update", "/get_full_mesh"};
  load.request.remap_target_args = {"/stereo_fusion/mesh_update", "/stereo_fusion/get_full_mesh"};
  ASSERT_TRUE(ros::service::waitForService("/base_station/load_nodelet", ros::Duration(30.0)));
  ASSERT_TRUE(ros::service::call("/base_station/load_nodelet", load));
  ASSERT_TRUE(load.response.success);
  SubmeshMap assembled, robot;
  uint64_t joined_sequence = 0, robot_sequence = 0, assembled_sequence = 0;
  ASSERT_TRUE(ros::service::waitForService("/mesh_assembler/get_full_mesh", ros::Duration(30.0)));
  // It fetches the robot's mesh on its own (late join): wait until it holds one.
  ASSERT_TRUE(test::waitFor([&] {
    return fetch("/mesh_assembler/get_full_mesh", &assembled, &joined_sequence) && joined_sequence > 0;
  }, 30.0));
  EXPECT_GT(assembled.size(), 5u) << "the full mesh fetched on joining is (nearly) empty";

  // Second half: the assembler follows the updates.
  for (int f = kFrames / 2; f < kFrames; ++f) publishFrame(f);
  ASSERT_TRUE(test::waitFor([&] { return diagnostics.value("frames fused") >= kFrames; }, 60.0));
  ASSERT_EQ(diagnostics.value("frames fused"), kFrames);
  ASSERT_TRUE(test::waitFor([&] {
    return fetch("/stereo_fusion/get_full_mesh", &robot, &robot_sequence) &&
           fetch("/mesh_assembler/get_full_mesh", &assembled, &assembled_sequence) &&
           assembled_sequence == robot_sequence;
  }, 30.0)) << "assembler at sequence " << assembled_sequence << ", robot at " << robot_sequence;
  EXPECT_GT(assembled_sequence, joined_sequence) << "no update was applied after joining";

  // Exactly the robot's mesh (in the compact mode both are the same decoded quantised values).
  ASSERT_EQ(assembled.size(), robot.size());
  for (const auto& [key, sub] : robot) {
    auto it = assembled.find(key);
    ASSERT_NE(it, assembled.end()) << key;
    EXPECT_EQ(it->second.positions, sub.positions) << key;
    EXPECT_EQ(it->second.normals, sub.normals) << key;
    EXPECT_EQ(it->second.colors, sub.colors) << key;
    EXPECT_EQ(it->second.triangles, sub.triangles) << key;
  }

  // And the mesh the offline pipeline builds from the same frames: exact in float32, within half
  // a quantisation step per axis in the compact encoding.
  const auto& expected = offline.mesh().submeshes();
  ASSERT_GT(expected.size(), 20u);
  ASSERT_EQ(assembled.size(), expected.size());
  const double half_step_m = compactPositionStep(8.0 * config.voxel_size_m) / 2.0 + 1e-6;
  double worst_m = 0.0, worst_normal = 0.0;
  size_t triangles = 0;
  for (const auto& [key, sub] : expected) {
    const SubMesh& got = assembled.at(key);
    ASSERT_EQ(got.positions.size(), sub.positions.size()) << key;
    EXPECT_EQ(got.triangles, sub.triangles) << key;
    EXPECT_EQ(got.colors, sub.colors) << key;
    triangles += sub.triangles.size();
    for (size_t v = 0; v < sub.positions.size(); ++v) {
      worst_m = std::max(worst_m, static_cast<double>((got.positions[v] - sub.positions[v]).cwiseAbs().maxCoeff()));
      worst_normal = std::max(worst_normal, static_cast<double>((got.normals[v] - sub.normals[v]).norm()));
    }
  }
  EXPECT_GT(triangles, 2000u);
  if (compact) {
    EXPECT_LE(worst_m, half_step_m);
    EXPECT_LT(worst_normal, 0.02);  // int8 normals: 1/127 per component
  } else {
    EXPECT_EQ(worst_m, 0.0);
    EXPECT_EQ(worst_normal, 0.0);
  }

  // ~save_mesh on both sides: the same welded PLY (float32: byte for byte).
  const std::string stem = "/tmp/stereo_fusion_assembler_" + std::to_string(getpid()) + "_" + encoding_name;
  SaveMesh save_robot, save_base;
  save_robot.request.path = stem + "_robot.ply";
  save_base.request.path = stem + "_base.ply";
  ASSERT_TRUE(ros::service::call("/stereo_fusion/save_mesh", save_robot));
  ASSERT_TRUE(ros::service::call("/mesh_assembler/save_mesh", save_base));
  ASSERT_TRUE(save_robot.response.success) << save_robot.response.message;
  ASSERT_TRUE(save_base.response.success) << save_base.response.message;
  const std::string robot_ply = readFile(save_robot.request.path), base_ply = readFile(save_base.request.path);
  EXPECT_GT(base_ply.size(), 1000u);
  if (!compact) EXPECT_TRUE(robot_ply == base_ply) << "the PLYs differ";
  else EXPECT_EQ(robot_ply.size(), base_ply.size());
  std::remove(save_robot.request.path.c_str());
  std::remove(save_base.request.path.c_str());

  // A gap: an update whose sequence skips one (as if the one before it was lost), carrying a
  // block the robot does not have. It must not be applied on top of a mesh that misses the lost
  // update: the assembler asks for the full mesh again and ends, after the next real frame, with
  // exactly the robot's mesh, without that block.
  ros::Publisher injector = nh.advertise<MeshUpdate>("/stereo_fusion/mesh_update", 1, true);
  MeshUpdate after_gap;
  after_gap.sequence = robot_sequence + 2;
  after_gap.voxel_size = static_cast<float>(config.voxel_size_m);
  after_gap.block_size = static_cast<float>(8.0 * config.voxel_size_m);
  SubMesh stray;
  stray.key = {1000, 1000, 1000};
  stray.positions = {{160.0f, 160.0f, 160.0f}, {160.1f, 160.0f, 160.0f}, {160.0f, 160.1f, 160.0f}};
  stray.normals.assign(3, Eigen::Vector3f::UnitZ());
  stray.colors.assign(3, {255, 0, 0});
  stray.triangles = {{0, 1, 2}};
  after_gap.blocks.push_back(toMeshBlock(stray));
  ASSERT_TRUE(test::waitFor([&] { return injector.getNumSubscribers() > 0; }, 30.0));
  injector.publish(after_gap);
  ros::WallDuration(1.0).sleep();  // let it arrive before the next real update
  publishFrame(kFrames);
  ASSERT_TRUE(test::waitFor([&] { return diagnostics.value("frames fused") >= kFrames + 1; }, 60.0));
  ASSERT_TRUE(test::waitFor([&] {
    return fetch("/stereo_fusion/get_full_mesh", &robot, &robot_sequence) &&
           fetch("/mesh_assembler/get_full_mesh", &assembled, &assembled_sequence) &&
           assembled_sequence == robot_sequence;
  }, 30.0)) << "assembler at sequence " << assembled_sequence << ", robot at " << robot_sequence;
  EXPECT_EQ(assembled.count(stray.key), 0u) << "the update after the gap was applied";
  ASSERT_EQ(assembled.size(), robot.size());
  for (const auto& [key, sub] : robot) {
    auto it = assembled.find(key);
    ASSERT_NE(it, assembled.end()) << key;
    EXPECT_EQ(it->second.positions, sub.positions) << key;
    EXPECT_EQ(it->second.triangles, sub.triangles) << key;
  }
}

int main(int argc, char** argv) { return test::runRosTests(argc, argv, "stereo_fusion_assembler_test"); }
