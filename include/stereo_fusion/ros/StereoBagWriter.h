#pragma once
#include <opencv2/core.hpp>

#include <memory>
#include <string>

#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/ros/BagSequence.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"

namespace rosbag {
class Bag;
}

namespace stereo_fusion {

/// Topics of a stereo camera driver: both images and both camera infos, before any stereo
/// matching. The defaults are the names stereo_image_proc expects under /stereo.
struct PairTopics {
  std::string left_image = "/stereo/left/image_raw";
  std::string right_image = "/stereo/right/image_raw";
  std::string left_info = "/stereo/left/camera_info";
  std::string right_info = "/stereo/right/camera_info";
  /// Empty: both images are colour (rgb8) raw images. Otherwise the pair is already rectified,
  /// as image_proc/rectify publishes it: `left_image` and `right_image` are mono8 and the left
  /// colour image goes here.
  std::string left_image_color;

  /// The topics of an already rectified pair (stereo_pipeline.launch rectified:=true):
  /// /stereo/{left,right}/image_rect (mono8) and /stereo/left/image_rect_color.
  static PairTopics rectified();
};

/// Records stereo frames as a rosbag a stereo camera pipeline would produce: DisparityImage,
/// Image, CameraInfo (the topics of BagTopics) and the pose on /tf. Stamps are the frames'
/// timestamps plus `stamp_offset_s`: ROS time 0 means "latest" to tf, so recordings must not
/// start there.
class StereoBagWriter {
 public:
  static std::unique_ptr<StereoBagWriter> open(const std::string& path, const BagTopics& topics,
                                               const std::string& camera_frame,
                                               double stamp_offset_s, std::string* error);
  ~StereoBagWriter();
  /// Writes one frame; false with a message on I/O failure.
  bool write(const StereoFrame& frame, float max_disparity_px, std::string* error);
  /// Writes one frame as a stereo camera driver publishes it (no disparity): the left colour
  /// image, `right_rgb` (CV_8UC3 RGB, rectified right camera), as PairTopics describes, both
  /// CameraInfos (distortion zero, R = I, the right P with Tx = -fx * baseline as stereo_image_proc
  /// needs it) on `topics`, and the left pose on /tf. Both images carry the left camera's frame_id:
  /// stereo_image_proc requires one frame for the pair (the baseline is in the right P). False with
  /// a message on I/O failure.
  bool writePair(const StereoFrame& frame, const cv::Mat& right_rgb, const PairTopics& topics,
                 std::string* error);
  /// Writes a SLAM's corrected trajectory as it publishes one after a loop closure: a
  /// nav_msgs/Path of `poses` (camera poses in the world frame, stamps shifted like the frames')
  /// on BagTopics::trajectory, stamped `stamp_s` (+ the offset). False with a message on I/O
  /// failure.
  bool writeTrajectory(const std::vector<StampedPose>& poses, double stamp_s, std::string* error);
  void close();

 private:
  StereoBagWriter() = default;
  std::unique_ptr<rosbag::Bag> bag_;
  BagTopics topics_;
  std::string camera_frame_;
  uint32_t frames_written_ =
      0;  // header.seq of the last frame written (numbered from 1, as drivers do)
  double stamp_offset_s_ = 0.0;
};

}  // namespace stereo_fusion
