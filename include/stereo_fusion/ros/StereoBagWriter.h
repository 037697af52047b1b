#pragma once
#include <memory>
#include <string>

#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/ros/BagSequence.h"

namespace rosbag {
class Bag;
}

namespace stereo_fusion {

/// Records stereo frames as a rosbag a stereo camera pipeline would produce: DisparityImage,
/// Image, CameraInfo (the topics of BagTopics) and the pose on /tf. Stamps are the frames'
/// timestamps plus `stamp_offset_s`: ROS time 0 means "latest" to tf, so recordings must not
/// start there.
class StereoBagWriter {
 public:
  static std::unique_ptr<StereoBagWriter> open(const std::string& path, const BagTopics& topics,
                                               const std::string& camera_frame, double stamp_offset_s,
                                               std::string* error);
  ~StereoBagWriter();
  /// Writes one frame; false with a message on I/O failure.
  bool write(const StereoFrame& frame, float max_disparity_px, std::string* error);
  void close();

 private:
  StereoBagWriter() = default;
  std::unique_ptr<rosbag::Bag> bag_;
  BagTopics topics_;
  std::string camera_frame_;
  double stamp_offset_s_ = 0.0;
};

}  // namespace stereo_fusion
