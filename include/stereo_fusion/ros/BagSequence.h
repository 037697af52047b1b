#pragma once
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <stereo_msgs/DisparityImage.h>
#include <tf2/buffer_core.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "stereo_fusion/io/FrameSource.h"

namespace stereo_fusion {

/// Topic names and frames read from a bag; the defaults are the nodelet's (stereo_image_proc's
/// names under /stereo).
struct BagTopics {
  std::string disparity = "/stereo/disparity";
  std::string image = "/stereo/left/image_rect_color";
  std::string camera_info = "/stereo/left/camera_info";
  std::string world_frame = "world";
  /// A SLAM's corrected trajectory (nav_msgs/Path in world_frame), written by the simulator with
  /// --drift; the nodelet's `trajectory` input.
  std::string trajectory = "/trajectory";
};

/// A rosbag as a FrameSource: DisparityImage + Image + CameraInfo matched by exact stamp, the
/// pose from /tf and /tf_static (T_world_camera at the disparity stamp, camera frame = the
/// disparity's frame_id). A frame without a matching image, camera info or transform fails to
/// load with the reason; the others load normally.
class BagSequence : public FrameSource {
 public:
  static std::unique_ptr<BagSequence> open(const std::string& path, const BagTopics& topics,
                                           std::string* error);

  size_t size() const override { return disparities_.size(); }
  bool load(size_t i, StereoFrame* frame, std::string* error) const override;

 private:
  BagTopics topics_;
  std::unique_ptr<tf2::BufferCore> tf_;
  std::vector<stereo_msgs::DisparityImage::ConstPtr> disparities_;
  std::vector<sensor_msgs::Image::ConstPtr> images_;
  std::vector<sensor_msgs::CameraInfo::ConstPtr> infos_;
};

}  // namespace stereo_fusion
