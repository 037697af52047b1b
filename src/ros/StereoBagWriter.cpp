#include "stereo_fusion/ros/StereoBagWriter.h"

#include <cv_bridge/cv_bridge.h>
#include <nav_msgs/Path.h>
#include <tf2_eigen/tf2_eigen.h>
#include <rosbag/bag.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_msgs/TFMessage.h>

#include <opencv2/imgproc.hpp>

#include "stereo_fusion/ros/MessageConversions.h"

namespace stereo_fusion {

PairTopics PairTopics::rectified() {
  PairTopics topics;
  topics.left_image = "/stereo/left/image_rect";
  topics.right_image = "/stereo/right/image_rect";
  topics.left_image_color = "/stereo/left/image_rect_color";
  return topics;
}

namespace {

/// What image_proc/rectify publishes as image_rect: mono8.
sensor_msgs::Image monoImage(const std_msgs::Header& header, const cv::Mat& rgb_or_grey) {
  cv::Mat grey = rgb_or_grey;
  if (rgb_or_grey.channels() == 3) cv::cvtColor(rgb_or_grey, grey, cv::COLOR_RGB2GRAY);
  return *cv_bridge::CvImage(header, sensor_msgs::image_encodings::MONO8, grey).toImageMsg();
}

}  // namespace

std::unique_ptr<StereoBagWriter> StereoBagWriter::open(const std::string& path,
                                                       const BagTopics& topics,
                                                       const std::string& camera_frame,
                                                       double stamp_offset_s, std::string* error) {
  std::unique_ptr<StereoBagWriter> writer(new StereoBagWriter());
  writer->topics_ = topics;
  writer->camera_frame_ = camera_frame;
  writer->stamp_offset_s_ = stamp_offset_s;
  try {
    writer->bag_ = std::make_unique<rosbag::Bag>(path, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& e) {
    *error = path + ": cannot write the bag: " + e.what();
    return nullptr;
  }
  return writer;
}

StereoBagWriter::~StereoBagWriter() { close(); }

bool StereoBagWriter::write(const StereoFrame& frame, float max_disparity_px, std::string* error) {
  std_msgs::Header header;
  header.seq = ++frames_written_;
  header.stamp = ros::Time(frame.timestamp_s + stamp_offset_s_);
  header.frame_id = camera_frame_;
  stereo_msgs::DisparityImage disparity;
  sensor_msgs::Image image;
  sensor_msgs::CameraInfo info;
  toMessages(frame, header, max_disparity_px, &disparity, &image, &info);
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(toTransform(frame.T_world_camera, topics_.world_frame, header));
  try {
    bag_->write("/tf", header.stamp, tf);
    bag_->write(topics_.disparity, header.stamp, disparity);
    bag_->write(topics_.image, header.stamp, image);
    bag_->write(topics_.camera_info, header.stamp, info);
  } catch (const rosbag::BagException& e) {
    *error = std::string("writing the bag failed: ") + e.what();
    return false;
  }
  return true;
}

bool StereoBagWriter::writeTrajectory(const std::vector<StampedPose>& poses, double stamp_s,
                                      std::string* error) {
  nav_msgs::Path path;
  path.header.stamp = ros::Time(stamp_s + stamp_offset_s_);
  path.header.frame_id = topics_.world_frame;
  for (const StampedPose& p : poses) {
    geometry_msgs::PoseStamped pose;
    pose.header.stamp = ros::Time(p.stamp_s + stamp_offset_s_);
    pose.header.frame_id = topics_.world_frame;
    pose.pose = tf2::toMsg(p.T_world_camera);
    path.poses.push_back(pose);
  }
  try {
    bag_->write(topics_.trajectory, path.header.stamp, path);
  } catch (const rosbag::BagException& e) {
    *error = std::string("writing the bag failed: ") + e.what();
    return false;
  }
  return true;
}

bool StereoBagWriter::writePair(const StereoFrame& frame, const cv::Mat& right_rgb,
                                const PairTopics& topics, std::string* error) {
  std_msgs::Header header;
  header.seq = ++frames_written_;
  header.stamp = ros::Time(frame.timestamp_s + stamp_offset_s_);
  header.frame_id = camera_frame_;
  stereo_msgs::DisparityImage unused_disparity;
  sensor_msgs::Image left;
  sensor_msgs::CameraInfo left_info;
  toMessages(frame, header, 0.0f, &unused_disparity, &left, &left_info);
  const bool rectified = !topics.left_image_color.empty();
  const sensor_msgs::Image right =
      rectified
          ? monoImage(header, right_rgb)
          : *cv_bridge::CvImage(header, sensor_msgs::image_encodings::RGB8, right_rgb).toImageMsg();
  sensor_msgs::CameraInfo right_info = left_info;
  // The right camera's projection: x_right = fx * (X - baseline) / Z + cx (ROS stereo convention).
  right_info.P[3] = -frame.camera.fx() * frame.camera.baseline();
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(toTransform(frame.T_world_camera, topics_.world_frame, header));
  try {
    bag_->write("/tf", header.stamp, tf);
    if (rectified) {
      bag_->write(topics.left_image, header.stamp, monoImage(header, frame.color));
      bag_->write(topics.left_image_color, header.stamp, left);
    } else {
      bag_->write(topics.left_image, header.stamp, left);
    }
    bag_->write(topics.right_image, header.stamp, right);
    bag_->write(topics.left_info, header.stamp, left_info);
    bag_->write(topics.right_info, header.stamp, right_info);
  } catch (const rosbag::BagException& e) {
    *error = std::string("writing the bag failed: ") + e.what();
    return false;
  }
  return true;
}

void StereoBagWriter::close() {
  if (bag_) bag_->close();
  bag_.reset();
}

}  // namespace stereo_fusion
