#pragma once
// The `trajectory` topic: a SLAM's corrected poses (nav_msgs/Path) as camera poses in
// world_frame, checked and handed to the session, which re-fuses the kept frames.
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>

#include <atomic>
#include <functional>
#include <string>

#include "stereo_fusion/ros/RosParameters.h"
#include "stereo_fusion/session/MappingSession.h"

namespace stereo_fusion {

class TrajectoryInput {
 public:
  /// `camera_frame()` gives the fused frames' camera frame ("" before the first).
  TrajectoryInput(ros::NodeHandle& nh, const NodeConfig& node, MappingSession* session,
                  const tf2_ros::Buffer* tf, std::function<std::string()> camera_frame);

  uint64_t received() const { return received_.load(); }

 private:
  void onTrajectory(const nav_msgs::Path::ConstPtr& path);
  void refuse(TrajectoryOutcome outcome, const std::string& why);

  const NodeConfig& node_;
  MappingSession* session_;
  const tf2_ros::Buffer* tf_;
  std::function<std::string()> camera_frame_;
  std::atomic<uint64_t> received_{0};
  ros::Subscriber sub_;
};

}  // namespace stereo_fusion
