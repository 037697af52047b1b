// toCameraPoses(): a SLAM's nav_msgs/Path as camera poses (src/ros/MessageConversions.cpp), the
// conversion the node's TrajectoryInput and the trajectory fuzz target share.
#include <gtest/gtest.h>

#include <cmath>

#include "stereo_fusion/ros/MessageConversions.h"

using namespace stereo_fusion;

namespace {

geometry_msgs::PoseStamped poseAt(double stamp_s, double x, double y, double z, double qx,
                                  double qy, double qz, double qw) {
  geometry_msgs::PoseStamped p;
  p.header.stamp = ros::Time(stamp_s);
  p.pose.position.x = x, p.pose.position.y = y, p.pose.position.z = z;
  p.pose.orientation.x = qx, p.pose.orientation.y = qy;
  p.pose.orientation.z = qz, p.pose.orientation.w = qw;
  return p;
}

}  // namespace

TEST(TrajectoryPoses, ComposeTheTrajectoryFrameWithTheCamera) {
  // Pose 1: 90° about z (q = (0, 0, sin 45°, cos 45°)) at (1, 2, 3); the camera sits 0.5 m along
  // the trajectory frame's x, so in the world it is at (1, 2, 3) + R_z(90°)·(0.5, 0, 0) =
  // (1, 2.5, 3).
  nav_msgs::Path path;
  path.poses.push_back(poseAt(10.0, 0, 0, 0, 0, 0, 0, 1));
  path.poses.push_back(poseAt(10.5, 1, 2, 3, 0, 0, std::sqrt(0.5), std::sqrt(0.5)));
  Eigen::Isometry3d T_trajectory_camera = Eigen::Isometry3d::Identity();
  T_trajectory_camera.translation() = Eigen::Vector3d(0.5, 0, 0);
  std::vector<StampedPose> poses;
  std::string why;
  ASSERT_TRUE(toCameraPoses(path, T_trajectory_camera, &poses, &why)) << why;
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_DOUBLE_EQ(poses[0].stamp_s, 10.0);
  EXPECT_DOUBLE_EQ(poses[1].stamp_s, 10.5);
  EXPECT_TRUE(poses[0].T_world_camera.translation().isApprox(Eigen::Vector3d(0.5, 0, 0)));
  EXPECT_TRUE(poses[1].T_world_camera.translation().isApprox(Eigen::Vector3d(1, 2.5, 3)));
  EXPECT_TRUE(poses[1].T_world_camera.linear().col(0).isApprox(Eigen::Vector3d(0, 1, 0)));
}

TEST(TrajectoryPoses, NormaliseANearlyUnitQuaternion) {
  // |q| = 1.005, within kMaxQuaternionNormError (0.01): taken as the identity, normalised.
  nav_msgs::Path path;
  path.poses.push_back(poseAt(1.0, 0, 0, 0, 0, 0, 0, 1.005));
  std::vector<StampedPose> poses;
  std::string why;
  ASSERT_TRUE(toCameraPoses(path, Eigen::Isometry3d::Identity(), &poses, &why)) << why;
  EXPECT_TRUE(poses[0].T_world_camera.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-12));
}

TEST(TrajectoryPoses, RefuseTheWholePathForOneBadPoseAndNameIt) {
  const geometry_msgs::PoseStamped good = poseAt(1.0, 0, 0, 0, 0, 0, 0, 1);
  const std::vector<std::pair<geometry_msgs::PoseStamped, std::string>> bad = {
      {poseAt(2.0, 0, 0, 0, 0, 0, 0, 0), "pose 1 of 3"},         // no rotation
      {poseAt(2.0, 0, 0, 0, 0, 0, 0, 2), "pose 1 of 3"},         // |q| = 2
      {poseAt(2.0, 0, 0, 0, 0, 0, 0, 1.02), "pose 1 of 3"},      // |q| off by 0.02 > 0.01
      {poseAt(2.0, 0, 0, 0, NAN, 0, 0, 1), "pose 1 of 3"},       // not finite
      {poseAt(2.0, INFINITY, 0, 0, 0, 0, 0, 1), "not finite"}};  // position
  for (const auto& [pose, expected] : bad) {
    nav_msgs::Path path;
    path.poses = {good, pose, good};
    std::vector<StampedPose> poses(1);  // untouched when refused
    std::string why;
    EXPECT_FALSE(toCameraPoses(path, Eigen::Isometry3d::Identity(), &poses, &why));
    EXPECT_NE(why.find(expected), std::string::npos) << why;
    EXPECT_NE(why.find("the whole path is refused"), std::string::npos) << why;
    EXPECT_EQ(poses.size(), 1u);
  }
}
