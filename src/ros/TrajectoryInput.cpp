#include "stereo_fusion/ros/TrajectoryInput.h"

#include <tf2_eigen/tf2_eigen.h>

#include "stereo_fusion/ros/MessageConversions.h"

namespace stereo_fusion {

TrajectoryInput::TrajectoryInput(ros::NodeHandle& nh, const NodeConfig& node,
                                 MappingSession* session, const tf2_ros::Buffer* tf,
                                 std::function<std::string()> camera_frame)
    : node_(node), session_(session), tf_(tf), camera_frame_(std::move(camera_frame)) {
  session_->setCorrectionListener([](const CorrectionReport& report) {
    const TrajectoryOutcomeInfo& info = trajectoryOutcomeInfo(report.outcome);
    if (report.outcome == TrajectoryOutcome::kApplied)
      ROS_INFO("stereo_fusion: correction applied (up to %.3f m / %.2f deg): %s",
               report.max_shift_m, report.max_rotation_deg, report.message.c_str());
    else if (report.outcome == TrajectoryOutcome::kFailed || info.rejected)
      ROS_ERROR("stereo_fusion: trajectory %s: %s", info.key, report.message.c_str());
    else
      ROS_INFO("stereo_fusion: trajectory %s: %s", info.key, report.message.c_str());
  });
  sub_ = nh.subscribe("trajectory", 5, &TrajectoryInput::onTrajectory, this);
}

void TrajectoryInput::refuse(TrajectoryOutcome outcome, const std::string& why) {
  session_->countTrajectory(outcome);
  ROS_ERROR_THROTTLE(5.0, "stereo_fusion: trajectory ignored (%llu so far): %s",
                     static_cast<unsigned long long>(session_->trajectories().rejected()),
                     why.c_str());
}

void TrajectoryInput::onTrajectory(const nav_msgs::Path::ConstPtr& path) {
  ++received_;
  if (!path->header.frame_id.empty() && path->header.frame_id != node_.world_frame)
    return refuse(
        TrajectoryOutcome::kRejectedWrongFrame,
        "it is in frame '" + path->header.frame_id + "', the map in '" + node_.world_frame + "'");
  const std::string camera_frame = camera_frame_();
  if (camera_frame.empty())
    return refuse(TrajectoryOutcome::kRejectedNoFrameYet, "no frame has been fused yet");
  // T_world_camera = T_world_trajectory · T_trajectory_camera (the identity for the camera's own
  // poses).
  Eigen::Isometry3d T_trajectory_camera = Eigen::Isometry3d::Identity();
  if (!node_.trajectory_frame.empty() && node_.trajectory_frame != camera_frame) {
    try {
      T_trajectory_camera = tf2::transformToEigen(
          tf_->lookupTransform(node_.trajectory_frame, camera_frame, ros::Time(0)));
    } catch (const tf2::TransformException& e) {
      return refuse(
          TrajectoryOutcome::kRejectedNoTransform,
          "no transform " + node_.trajectory_frame + " <- " + camera_frame + ": " + e.what());
    }
  }
  std::vector<StampedPose> poses;
  std::string why;
  if (!toCameraPoses(*path, T_trajectory_camera, &poses, &why))
    return refuse(TrajectoryOutcome::kRejectedBadPose, why);
  const std::optional<CorrectionReport> refused = session_->submitTrajectory(std::move(poses));
  if (refused)
    ROS_ERROR_THROTTLE(5.0, "stereo_fusion: trajectory ignored (%llu so far): %s",
                       static_cast<unsigned long long>(session_->trajectories().rejected()),
                       refused->message.c_str());
}

}  // namespace stereo_fusion
