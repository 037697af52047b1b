// A base-station MeshAssembler that joins mid-run (loaded into a running nodelet manager after
// half of the frames were fused) ends with exactly the robot's mesh, and with the mesh an offline
// Mapper builds from the same frames (within the stated quantisation step when the robot sends
// the compact encoding). Its ~save_mesh writes the same PLY as the robot's; with texture patches
// on the robot (mesh_assembler_textured.test) its ~get_full_mesh carries the robot's patches and
// its ~save_mesh writes the robot's textured OBJ. It repairs its copy after a lost update, after
// a restart of the robot (a new session) and ignores a stale full update.
#include <nodelet/NodeletLoad.h>
#include <stereo_fusion/SaveMesh.h>
#include <tf2_ros/transform_broadcaster.h>
#include <unistd.h>

#include <fstream>
#include <map>

#include "../unit/TestSupport.h"
#include "FullMeshSupport.h"
#include "NodeletUnload.h"
#include "RosTestSupport.h"
#include "readers/ObjReader.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/ros/MeshAssembler.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/MessageConversions.h"
#include "stereo_fusion/ros/RosParameters.h"

using namespace stereo_fusion;

namespace {

using test::SubmeshMap;

sim::AnalyticScene scene() {
  sim::AnalyticScene s;
  s.add(sim::makePlane({0, 0.3, 0}, {0, -1, 0}), {180, 160, 120});
  s.add(sim::makeSphere({0.05, 0.1, 1.2}, 0.2), {200, 60, 60});
  s.add(sim::makeBox(Eigen::Isometry3d(Eigen::Translation3d(-0.35, 0.15, 1.0)), {0.1, 0.15, 0.1}),
        {60, 160, 60});
  return s;
}

/// Blocks of `update` by key.
std::map<BlockKey, const MeshBlock*> blocksOf(const MeshUpdate& update) {
  std::map<BlockKey, const MeshBlock*> blocks;
  for (const MeshBlock& b : update.blocks) blocks[{b.key[0], b.key[1], b.key[2]}] = &b;
  return blocks;
}

}  // namespace

TEST(MeshAssembler, JoinedMidRunEndsWithExactlyTheRobotsMesh) {
  ros::NodeHandle nh;
  std::string encoding_name;
  ASSERT_TRUE(nh.getParam("/stereo_fusion/mesh_encoding", encoding_name));
  const bool compact = encoding_name == "compact";
  const bool textured = nh.param<std::string>("/stereo_fusion/texture", "off") == "patches";
  auto disparity_pub = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 20);
  auto image_pub = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 20);
  auto info_pub = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 20);
  tf2_ros::TransformBroadcaster tf;
  test::DiagnosticsWatcher diagnostics;
  test::DiagnosticsWatcher assembler_diagnostics("mesh assembler");
  ASSERT_TRUE(test::waitFor(
      [&] {
        return disparity_pub.getNumSubscribers() > 0 && image_pub.getNumSubscribers() > 0 &&
               info_pub.getNumSubscribers() > 0;
      },
      30.0))
      << "the fusion nodelet did not connect";
  ASSERT_TRUE(test::waitForTfSubscriber(30.0)) << "the nodelet's tf listener did not connect";

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
    const StereoFrame frame =
        test::renderFrame(s, camera, sim::lookAt(eye, {0.0, 0.1, 1.1}, -Eigen::Vector3d::UnitY()));
    const test::FrameMessages m = test::frameMessages(frame, &tf);
    // The offline reference sees exactly what the nodelet sees: the messages, converted back.
    StereoFrame received;
    ASSERT_TRUE(
        toStereoFrame(m.disparity, m.image, m.info, frame.T_world_camera, &received, &error))
        << error;
    ASSERT_TRUE(offline.integrate(received).accepted);
    ros::WallDuration(0.05).sleep();  // tf first, as a SLAM stack running ahead would
    disparity_pub.publish(m.disparity);
    image_pub.publish(m.image);
    info_pub.publish(m.info);
  };

  // First half: nobody at the base station yet.
  for (int f = 0; f < kFrames / 2; ++f) publishFrame(f);
  ASSERT_TRUE(test::waitFor([&] { return diagnostics.value("frames fused") >= kFrames / 2; }, 60.0))
      << "fused " << diagnostics.value("frames fused") << " of "
      << diagnostics.value("frames received") << " received; dropped: tf "
      << diagnostics.value("dropped: tf timeout") << ", queue "
      << diagnostics.value("dropped: queue full");

  // The base station joins: MeshAssembler loaded into the running manager, remapped to the robot.
  // With ~assembler_launched (test/ros/install_space/base_station.test) it is instead the
  // mesh_assembler node base_station.launch started beside the robot: the same checks follow.
  if (!ros::NodeHandle("~").param("assembler_launched", false)) {
    nodelet::NodeletLoad load;
    load.request.name = "/mesh_assembler";
    load.request.type = "stereo_fusion/MeshAssembler";
    load.request.remap_source_args = {"/mesh_update", "/get_full_mesh"};
    load.request.remap_target_args = {"/stereo_fusion/mesh_update", "/stereo_fusion/get_full_mesh"};
    ASSERT_TRUE(ros::service::waitForService("/base_station/load_nodelet", ros::Duration(30.0)));
    ASSERT_TRUE(ros::service::call("/base_station/load_nodelet", load));
    ASSERT_TRUE(load.response.success);
  }
  SubmeshMap assembled, robot;
  uint64_t joined_sequence = 0, robot_sequence = 0, assembled_sequence = 0;
  ASSERT_TRUE(ros::service::waitForService("/mesh_assembler/get_full_mesh", ros::Duration(30.0)));
  // It fetches the robot's mesh on its own (late join): wait until it holds one.
  ASSERT_TRUE(test::waitFor(
      [&] {
        return test::fetchFullMesh("/mesh_assembler/get_full_mesh", &assembled, &joined_sequence) &&
               joined_sequence > 0;
      },
      30.0));
  EXPECT_GT(assembled.size(), 5u) << "the full mesh fetched on joining is (nearly) empty";

  // Second half: the assembler follows the updates.
  for (int f = kFrames / 2; f < kFrames; ++f) publishFrame(f);
  ASSERT_TRUE(test::waitFor([&] { return diagnostics.value("frames fused") >= kFrames; }, 60.0));
  ASSERT_EQ(diagnostics.value("frames fused"), kFrames);
  ASSERT_TRUE(test::waitForAssemblerToCatchUp(&robot, &robot_sequence, &assembled,
                                              &assembled_sequence, 30.0))
      << "assembler at sequence " << assembled_sequence << ", robot at " << robot_sequence;
  EXPECT_GT(assembled_sequence, joined_sequence) << "no update was applied after joining";
  // Followed incrementally: one full mesh fetched on joining, none since (a refetch per update
  // would reach the same mesh, so only the count tells them apart).
  ASSERT_TRUE(assembler_diagnostics.waitForNextReport(10.0));
  EXPECT_EQ(assembler_diagnostics.value("full mesh requests"), 1);
  EXPECT_EQ(assembler_diagnostics.value("sequence gaps"), 0);

  // Exactly the robot's mesh (in the compact mode both are the same decoded quantised values).
  test::expectSameSubmeshes(assembled, robot, test::kWithColors | test::kWithNormals);

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
      worst_m = std::max(worst_m, static_cast<double>(
                                      (got.positions[v] - sub.positions[v]).cwiseAbs().maxCoeff()));
      worst_normal =
          std::max(worst_normal, static_cast<double>((got.normals[v] - sub.normals[v]).norm()));
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
  const std::string stem =
      "/tmp/stereo_fusion_assembler_" + std::to_string(getpid()) + "_" + encoding_name;
  SaveMesh save_robot, save_base;
  save_robot.request.path = stem + "_robot.ply";
  save_base.request.path = stem + "_base.ply";
  ASSERT_TRUE(ros::service::call("/stereo_fusion/save_mesh", save_robot));
  ASSERT_TRUE(ros::service::call("/mesh_assembler/save_mesh", save_base));
  ASSERT_TRUE(save_robot.response.success) << save_robot.response.message;
  ASSERT_TRUE(save_base.response.success) << save_base.response.message;
  const std::string robot_ply = test::readFileBytes(save_robot.request.path),
                    base_ply = test::readFileBytes(save_base.request.path);
  EXPECT_GT(base_ply.size(), 1000u);
  if (!compact)
    EXPECT_TRUE(robot_ply == base_ply) << "the PLYs differ";
  else
    EXPECT_EQ(robot_ply.size(), base_ply.size());
  std::remove(save_robot.request.path.c_str());
  std::remove(save_base.request.path.c_str());

  if (textured) {
    // The assembler keeps the patches: its full mesh carries the robot's UVs and PNG bytes.
    MeshUpdate robot_raw, base_raw;
    SubmeshMap unused;
    uint64_t sequence = 0;
    ASSERT_TRUE(
        test::fetchFullMesh("/stereo_fusion/get_full_mesh", &unused, &sequence, &robot_raw));
    ASSERT_TRUE(
        test::fetchFullMesh("/mesh_assembler/get_full_mesh", &unused, &sequence, &base_raw));
    const auto robot_blocks = blocksOf(robot_raw), base_blocks = blocksOf(base_raw);
    ASSERT_EQ(base_blocks.size(), robot_blocks.size());
    size_t textured_blocks = 0;
    for (const auto& [key, b] : robot_blocks) {
      ASSERT_EQ(base_blocks.count(key), 1u) << key;
      EXPECT_EQ(base_blocks.at(key)->uvs, b->uvs) << key;
      EXPECT_TRUE(base_blocks.at(key)->texture.data == b->texture.data) << key;
      textured_blocks += !b->uvs.empty();
    }
    EXPECT_GT(textured_blocks, 3u);

    // ~save_mesh with .obj: OBJ + MTL + atlas, readable, with textured blocks; float32: the
    // same files as the robot's.
    save_robot.request.path = stem + "_robot.obj";
    save_base.request.path = stem + "_base.obj";
    ASSERT_TRUE(ros::service::call("/stereo_fusion/save_mesh", save_robot));
    ASSERT_TRUE(ros::service::call("/mesh_assembler/save_mesh", save_base));
    ASSERT_TRUE(save_robot.response.success) << save_robot.response.message;
    ASSERT_TRUE(save_base.response.success) << save_base.response.message;
    ObjMesh obj;
    ASSERT_TRUE(readObj(save_base.request.path, &obj, &error)) << error;
    size_t triangles = 0;
    for (const auto& [key, sub] : assembled) triangles += sub.triangles.size();
    EXPECT_EQ(obj.faces.size(), triangles);
    size_t faces_with_uvs = 0;
    for (const ObjFace& f : obj.faces) faces_with_uvs += f.vt[0] >= 0;
    EXPECT_EQ(faces_with_uvs, triangles);
    bool atlas_found = false;
    for (const ObjMaterial& m : obj.materials)
      atlas_found |= !m.diffuse_map.empty() && std::ifstream(m.diffuse_map).good();
    EXPECT_TRUE(atlas_found);
    // "wrote <N> textured and <M> vertex-coloured blocks to ...", as the robot's.
    EXPECT_EQ(save_base.response.message.rfind("wrote ", 0), 0u) << save_base.response.message;
    EXPECT_EQ(std::stoul(save_base.response.message.substr(6)), textured_blocks)
        << save_base.response.message;
    if (!compact) {
      // The OBJs differ only in the name of their MTL file (mtllib line).
      std::string robot_obj = test::readFileBytes(save_robot.request.path);
      const size_t mtllib = robot_obj.find("_robot.mtl");
      ASSERT_NE(mtllib, std::string::npos);
      robot_obj.replace(mtllib, 6, "_base");
      EXPECT_TRUE(robot_obj == test::readFileBytes(save_base.request.path)) << "the OBJs differ";
      for (const ObjMaterial& m : obj.materials) {
        const std::string robot_png =
            std::string(m.diffuse_map).replace(m.diffuse_map.rfind("_base"), 5, "_robot");
        EXPECT_TRUE(test::readFileBytes(robot_png) == test::readFileBytes(m.diffuse_map))
            << m.diffuse_map;
      }
    }
    for (const ObjMaterial& m : obj.materials) {
      std::remove(m.diffuse_map.c_str());
      std::remove(
          std::string(m.diffuse_map).replace(m.diffuse_map.rfind("_base"), 5, "_robot").c_str());
    }
    for (const std::string& path : {save_robot.request.path, save_base.request.path}) {
      std::remove(path.c_str());
      std::remove((path.substr(0, path.size() - 4) + ".mtl").c_str());
    }
  }

  // A gap: an update whose sequence skips one (as if the one before it was lost), carrying a
  // block the robot does not have. It must not be applied on top of a mesh that misses the lost
  // update: the assembler asks for the full mesh again and ends, after the next real frame, with
  // exactly the robot's mesh, without that block.
  ros::Publisher injector = nh.advertise<MeshUpdate>("/stereo_fusion/mesh_update", 1, true);
  MeshUpdate session_probe;
  ASSERT_TRUE(
      test::fetchFullMesh("/stereo_fusion/get_full_mesh", &robot, &robot_sequence, &session_probe));
  MeshUpdate after_gap;
  after_gap.session = session_probe.session;  // the robot's own run: a gap, not a restart
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
  // It must arrive before the next real update: the assembler counts the gap when it does.
  ASSERT_TRUE(
      test::waitFor([&] { return assembler_diagnostics.value("sequence gaps") >= 1; }, 30.0));
  publishFrame(kFrames);
  ASSERT_TRUE(
      test::waitFor([&] { return diagnostics.value("frames fused") >= kFrames + 1; }, 60.0));
  ASSERT_TRUE(test::waitForAssemblerToCatchUp(&robot, &robot_sequence, &assembled,
                                              &assembled_sequence, 30.0))
      << "assembler at sequence " << assembled_sequence << ", robot at " << robot_sequence;
  EXPECT_EQ(assembled.count(stray.key), 0u) << "the update after the gap was applied";
  test::expectSameSubmeshes(assembled, robot);
  // Repaired, and not silently: the gap is counted on /diagnostics.
  EXPECT_TRUE(
      test::waitFor([&] { return assembler_diagnostics.value("sequence gaps") >= 1; }, 10.0))
      << "sequence gaps reported: " << assembler_diagnostics.value("sequence gaps");

  // A restart of the robot: its sequence begins again, so a restarted robot's update can carry
  // exactly the sequence the assembler expects next while its mesh has nothing to do with the
  // one held. Only the session tells. An update of a new session with the next sequence number
  // must make the assembler refetch (here it gets the running robot's mesh, of the old session,
  // and drops the foreign update) instead of applying it on top.
  MeshUpdate robot_raw, base_raw;
  ASSERT_TRUE(
      test::fetchFullMesh("/stereo_fusion/get_full_mesh", &robot, &robot_sequence, &robot_raw));
  ASSERT_NE(robot_raw.session, 0u) << "the robot sends no session";
  ASSERT_TRUE(test::fetchFullMesh("/mesh_assembler/get_full_mesh", &assembled, &assembled_sequence,
                                  &base_raw));
  ASSERT_EQ(assembled_sequence, robot_sequence);
  EXPECT_EQ(base_raw.session, robot_raw.session);
  MeshUpdate restarted = after_gap;
  restarted.session = robot_raw.session + 1;
  restarted.sequence = robot_sequence + 1;
  injector.publish(restarted);
  ASSERT_TRUE(
      test::waitFor([&] { return assembler_diagnostics.value("robot restarts") >= 1; }, 30.0));
  // And a stale full update of the robot's own session (older than what the assembler holds,
  // e.g. a late reply): ignored, not a replacement of the mesh by an old one.
  MeshUpdate stale_full = after_gap;
  stale_full.session = robot_raw.session;
  stale_full.sequence = robot_sequence - 1;
  stale_full.full = true;
  injector.publish(stale_full);
  ros::WallDuration(1.0).sleep();  // ignoring leaves no trace to wait for: give it time to arrive
  ASSERT_TRUE(test::fetchFullMesh("/mesh_assembler/get_full_mesh", &assembled, &assembled_sequence,
                                  &base_raw));
  EXPECT_EQ(assembled.count(stray.key), 0u)
      << "an update of another session or a stale full update was applied";
  EXPECT_EQ(base_raw.session, robot_raw.session);
  EXPECT_EQ(assembled_sequence, robot_sequence);
  publishFrame(kFrames + 1);
  ASSERT_TRUE(
      test::waitFor([&] { return diagnostics.value("frames fused") >= kFrames + 2; }, 60.0));
  ASSERT_TRUE(test::waitForAssemblerToCatchUp(&robot, &robot_sequence, &assembled,
                                              &assembled_sequence, 30.0))
      << "assembler at sequence " << assembled_sequence << ", robot at " << robot_sequence;
  EXPECT_EQ(assembled.count(stray.key), 0u);
  test::expectSameSubmeshes(assembled, robot);
  EXPECT_TRUE(
      test::waitFor([&] { return assembler_diagnostics.value("robot restarts") >= 1; }, 10.0))
      << "robot restarts reported: " << assembler_diagnostics.value("robot restarts");
  ASSERT_TRUE(assembler_diagnostics.waitForNextReport(10.0));
  // The join 1; the gap 2 (at the update after the gap, whose fetched mesh is still behind it,
  // and again at the next real update, the retry); the restart 1; the stale full update none.
  EXPECT_EQ(assembler_diagnostics.value("full mesh requests"), 4);
  EXPECT_EQ(assembler_diagnostics.value("sequence gaps"), 1);
  EXPECT_EQ(assembler_diagnostics.value("malformed updates"), 0);
}

// Last in this file: the probe runs beside the launched assembler, in a namespace of its own.
TEST(NodeletUnload, QueuesLiveUntilTheNodeletIsDestroyed) {
  test::expectQueuesLiveUntilTheNodeletIsDestroyed<MeshAssembler>("/queue_probe/mesh_assembler");
}

int main(int argc, char** argv) {
  return test::runRosTests(argc, argv, "stereo_fusion_assembler_test");
}
