#pragma once
// ROS messages ↔ core types. The ros/ folder is the only place that includes ROS headers.

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Path.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <stereo_msgs/DisparityImage.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "stereo_fusion/camera/DepthToDisparity.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"

namespace stereo_fusion {

/// Builds a StereoFrame from one synchronised set of messages and the pose of the disparity's
/// frame. Camera: fx, fy, cx, cy from the rectified projection P (K when P is unset); baseline
/// from DisparityImage::T. Disparity must be 32FC1; values ≤ 0, non-finite or below
/// min_disparity become invalid (0). Colour: rgb8, bgr8, rgba8, bgra8, mono8. Any
/// inconsistency (sizes, encodings, zero f or T, focal lengths that disagree) returns false
/// with a message; nothing is half-filled.
bool toStereoFrame(const stereo_msgs::DisparityImage& disparity, const sensor_msgs::Image& image,
                   const sensor_msgs::CameraInfo& info, const Eigen::Isometry3d& T_world_camera,
                   StereoFrame* frame, std::string* error);

/// Builds a StereoFrame from a depth image registered to the colour image (same size, the
/// colour camera's CameraInfo) and the pose of the depth's frame: the depth becomes the
/// disparity fx·B/z of `converter`'s virtual rig (16UC1 mm with 0 invalid, 32FC1 m with
/// non-finite or ≤ 0 invalid), the camera's baseline is B. Colour as toStereoFrame(). Any
/// inconsistency (encoding, sizes, data length, calibration) returns false with a message.
bool depthToStereoFrame(const sensor_msgs::Image& depth, const sensor_msgs::Image& image,
                        const sensor_msgs::CameraInfo& info, const DepthToDisparity& converter,
                        const Eigen::Isometry3d& T_world_camera, StereoFrame* frame,
                        std::string* error);

/// The camera poses a SLAM's Path stands for: T_world_camera = pose_k · T_trajectory_camera,
/// stamped by each pose's header. A pose whose position or stamp is not finite, or whose
/// quaternion is no rotation (unitQuaternion(): one slightly off unit length is normalised),
/// refuses the whole Path: false, `poses` untouched, `why` names the pose.
bool toCameraPoses(const nav_msgs::Path& path, const Eigen::Isometry3d& T_trajectory_camera,
                   std::vector<StampedPose>* poses, std::string* why);

/// The messages a stereo pipeline publishes for `frame`, stamped with `header`: disparity as
/// 32FC1 with f, T and the disparity range [0, max_disparity_px]; the image as rgb8 (or mono8);
/// CameraInfo with K and P of the rectified left camera.
void toMessages(const StereoFrame& frame, const std_msgs::Header& header, float max_disparity_px,
                stereo_msgs::DisparityImage* disparity, sensor_msgs::Image* image,
                sensor_msgs::CameraInfo* info);

/// T_world_camera as the tf transform world_frame → camera_header.frame_id.
geometry_msgs::TransformStamped toTransform(const Eigen::Isometry3d& T_world_camera,
                                            const std::string& world_frame,
                                            const std_msgs::Header& camera_header);

/// Whether a message stamped `stamp` is more than `max_ahead_s` ahead of the clock `now`
/// (false when the check is off: max_ahead_s ≤ 0, or no clock yet: now = 0). In seconds as
/// doubles: ros::Time's difference throws beyond ±2³¹ s, which a broken driver's stamp reaches.
bool stampAheadOfClock(const ros::Time& stamp, const ros::Time& now, double max_ahead_s);

}  // namespace stereo_fusion
