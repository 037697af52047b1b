// The base station on another host. test/ros/two_hosts.sh runs the robot (its master, the fusion
// nodelet replaying a bag) and the base station (base_station.launch's mesh assembler and this
// node) in two network namespaces joined only by a veth pair, each side with ROS_IP set to its
// own address. Every node advertises the address of its own side, and the assembler, across the
// link, ends with exactly the robot's mesh (the same PLY, byte for byte).
#include <ros/network.h>
#include <stereo_fusion/SaveMesh.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "FullMeshSupport.h"
#include "RosTestSupport.h"
#include "stereo_fusion/ros/BagSequence.h"

using namespace stereo_fusion;

namespace {

/// The host of `node`'s XML-RPC URI as the master holds it ("" if the master does not know it).
std::string advertisedHost(const std::string& node) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  args[1] = node;
  if (!ros::master::execute("lookupNode", args, result, payload, false)) return "";
  const std::string uri = static_cast<std::string>(payload);  // http://host:port/
  const size_t begin = uri.find("://") + 3, end = uri.rfind(':');
  return end > begin ? uri.substr(begin, end - begin) : uri;
}

}  // namespace

TEST(TwoHosts, BaseStationAssemblesExactlyTheRobotsMesh) {
  ros::NodeHandle pnh("~");
  std::string bag_path, robot_ip, base_ip, error;
  ASSERT_TRUE(pnh.getParam("bag", bag_path));
  ASSERT_TRUE(pnh.getParam("robot_ip", robot_ip));
  ASSERT_TRUE(pnh.getParam("base_ip", base_ip));
  auto bag = BagSequence::open(bag_path, BagTopics{}, &error);
  ASSERT_TRUE(bag) << error;
  const long frames = static_cast<long>(bag->size());
  ASSERT_GT(frames, 5);

  EXPECT_EQ(ros::master::getHost(), robot_ip) << "ROS_MASTER_URI is not the robot's master";
  EXPECT_EQ(ros::network::getHost(), base_ip) << "this node does not advertise ROS_IP";
  ASSERT_TRUE(ros::service::waitForService("/mesh_assembler/get_full_mesh", ros::Duration(60.0)))
      << "the base station's assembler did not start";
  ASSERT_TRUE(ros::service::waitForService("/stereo_fusion/get_full_mesh", ros::Duration(60.0)))
      << "the robot's fusion nodelet is not reachable from the base station";

  // The robot's diagnostics reach the base station; the bag starts (a service call to the
  // robot's player) once the nodelet runs, and every frame of it is fused.
  test::DiagnosticsWatcher diagnostics;
  test::DiagnosticsWatcher assembler_diagnostics("mesh assembler");
  ASSERT_TRUE(test::startPausedPlayer(diagnostics)) << "the robot's player did not start";
  // Each side advertises its own veth address (the player is registered: it answered). A node
  // advertising localhost (ROS_HOSTNAME left at localhost) sends the other side to itself.
  EXPECT_EQ(advertisedHost("/stereo_fusion_manager"), robot_ip);
  EXPECT_EQ(advertisedHost("/player"), robot_ip);
  EXPECT_EQ(advertisedHost("/mesh_assembler"), base_ip);
  test::waitFor([&] { return diagnostics.value("frames fused") >= frames; }, 120.0);
  ASSERT_EQ(diagnostics.value("frames fused"), frames)
      << "received " << diagnostics.value("frames received") << ", dropped "
      << diagnostics.droppedTotal();

  // The assembler follows the robot's updates over the link to the robot's last sequence.
  test::SubmeshMap robot, assembled;
  uint64_t robot_sequence = 0, assembled_sequence = 0;
  ASSERT_TRUE(test::waitForAssemblerToCatchUp(&robot, &robot_sequence, &assembled,
                                              &assembled_sequence, 30.0))
      << "assembler at sequence " << assembled_sequence << ", robot at " << robot_sequence;
  EXPECT_GT(robot.size(), 5u) << "the robot's mesh is (nearly) empty";
  test::expectSameSubmeshes(assembled, robot, test::kWithColors | test::kWithNormals);
  ASSERT_TRUE(assembler_diagnostics.waitForNextReport(10.0));
  EXPECT_EQ(assembler_diagnostics.value("sequence gaps"), 0);
  EXPECT_EQ(assembler_diagnostics.value("malformed updates"), 0);

  // ~save_mesh on each side, each file written by its own host's process: the same welded PLY,
  // byte for byte (the robot sends float32, the default mesh_encoding).
  ASSERT_EQ(ros::param::param<std::string>("/stereo_fusion/mesh_encoding", "float32"), "float32");
  const std::string stem = "/tmp/stereo_fusion_two_hosts_" + std::to_string(getpid());
  SaveMesh save_robot, save_base;
  save_robot.request.path = stem + "_robot.ply";
  save_base.request.path = stem + "_base.ply";
  ASSERT_TRUE(ros::service::call("/stereo_fusion/save_mesh", save_robot));
  ASSERT_TRUE(ros::service::call("/mesh_assembler/save_mesh", save_base));
  ASSERT_TRUE(save_robot.response.success) << save_robot.response.message;
  ASSERT_TRUE(save_base.response.success) << save_base.response.message;
  const std::string robot_ply = test::readFileBytes(save_robot.request.path),
                    base_ply = test::readFileBytes(save_base.request.path);
  std::remove(save_robot.request.path.c_str());
  std::remove(save_base.request.path.c_str());
  EXPECT_GT(base_ply.size(), 1000u);
  EXPECT_TRUE(robot_ply == base_ply) << "the PLYs differ: robot " << robot_ply.size()
                                     << " B, base station " << base_ply.size() << " B";
}

int main(int argc, char** argv) { return test::runRosTests(argc, argv, "two_hosts_check"); }
