#pragma once
#include <memory>
#include <string>

#include "stereo_fusion/io/FrameSource.h"

namespace stereo_fusion {

/// Topic names and frames read from a bag; the defaults are the nodelet's (stereo_image_proc's
/// names under /stereo).
struct BagTopics {
  std::string disparity = "/stereo/disparity";
  std::string image = "/stereo/left/image_rect_color";
  std::string camera_info = "/stereo/left/camera_info";
  std::string world_frame = "map";  ///< the nodelet's default world_frame (REP 105)
  /// A SLAM's corrected trajectory (nav_msgs/Path in world_frame), written by the simulator with
  /// --drift; the nodelet's `trajectory` input.
  std::string trajectory = "/trajectory";
};

/// A rosbag as a FrameSource: DisparityImage + Image + CameraInfo matched by exact stamp, the
/// pose from /tf and /tf_static (T_world_camera at the disparity stamp, camera frame = the
/// disparity's frame_id). A frame without a matching image, camera info or transform fails to
/// load with the reason; the others load normally.
///
/// The bag is read as a stream: open() reads every message of the five topics once to index the
/// frames — where each frame's three messages lie in the bag and their header stamps, not their
/// images — and keeps the transforms (tf2's buffer: every /tf and /tf_static message of the
/// recording); load(i) reads frame i's three messages from the still open bag. Memory does not grow
/// with the bag's images: a few hundred bytes per frame, plus the transforms (small for a camera's
/// pose per frame; a recording with many frames on /tf at a high rate keeps them all). load() may
/// be called from several threads (the bag is read under a lock).
class BagSequence : public FrameSource {
 public:
  static std::unique_ptr<BagSequence> open(const std::string& path, const BagTopics& topics,
                                           std::string* error);
  ~BagSequence() override;

  size_t size() const override;
  bool load(size_t i, StereoFrame* frame, std::string* error) const override;

 private:
  BagSequence();
  struct Index;
  std::unique_ptr<Index> index_;
};

}  // namespace stereo_fusion
