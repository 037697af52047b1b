#include "stereo_fusion/ros/BagSequence.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include <map>

#include "stereo_fusion/ros/MessageConversions.h"

namespace stereo_fusion {

std::unique_ptr<BagSequence> BagSequence::open(const std::string& path, const BagTopics& topics,
                                               std::string* error) {
  auto seq = std::unique_ptr<BagSequence>(new BagSequence());
  seq->topics_ = topics;
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
    rosbag::View all(bag);
    if (all.size() == 0) {
      *error = path + ": the bag holds no messages";
      return nullptr;
    }
    // Keep every transform of the recording: frames are looked up after reading it all.
    const ros::Duration span = all.getEndTime() - all.getBeginTime() + ros::Duration(60.0);
    seq->tf_ = std::make_unique<tf2::BufferCore>(span);
    std::map<ros::Time, sensor_msgs::Image::ConstPtr> images;
    std::vector<sensor_msgs::CameraInfo::ConstPtr> infos;
    rosbag::View view(bag, rosbag::TopicQuery({topics.disparity, topics.image, topics.camera_info,
                                               "/tf", "/tf_static"}));
    for (const rosbag::MessageInstance& m : view) {
      if (m.getTopic() == "/tf" || m.getTopic() == "/tf_static") {
        if (auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
          const bool is_static = m.getTopic() == "/tf_static";
          for (const auto& t : tf->transforms) seq->tf_->setTransform(t, "bag", is_static);
        }
      } else if (m.getTopic() == topics.disparity) {
        if (auto d = m.instantiate<stereo_msgs::DisparityImage>()) seq->disparities_.push_back(d);
      } else if (m.getTopic() == topics.image) {
        if (auto im = m.instantiate<sensor_msgs::Image>()) images[im->header.stamp] = im;
      } else if (m.getTopic() == topics.camera_info) {
        if (auto ci = m.instantiate<sensor_msgs::CameraInfo>()) infos.push_back(ci);
      }
    }
    bag.close();
    if (seq->disparities_.empty()) {
      *error = path + ": no stereo_msgs/DisparityImage on topic " + topics.disparity;
      return nullptr;
    }
    for (const auto& d : seq->disparities_) {
      auto im = images.find(d->header.stamp);
      seq->images_.push_back(im == images.end() ? nullptr : im->second);
      // Camera info rarely changes: the latest one not after the frame (or the first one).
      sensor_msgs::CameraInfo::ConstPtr best = infos.empty() ? nullptr : infos.front();
      for (const auto& ci : infos)
        if (ci->header.stamp <= d->header.stamp) best = ci;
      seq->infos_.push_back(best);
    }
  } catch (const rosbag::BagException& e) {
    *error = path + ": cannot read the bag: " + e.what();
    return nullptr;
  }
  return seq;
}

bool BagSequence::load(size_t i, StereoFrame* frame, std::string* error) const {
  if (i >= disparities_.size()) {
    *error = "frame " + std::to_string(i) + " is out of range";
    return false;
  }
  const auto& d = *disparities_[i];
  const std::string where =
      "frame " + std::to_string(i) + " (stamp " + std::to_string(d.header.stamp.toSec()) + ")";
  if (!images_[i]) {
    *error = where + ": no image on " + topics_.image + " with the same stamp";
    return false;
  }
  if (!infos_[i]) {
    *error = where + ": no CameraInfo on " + topics_.camera_info;
    return false;
  }
  Eigen::Isometry3d T_world_camera;
  try {
    T_world_camera = tf2::transformToEigen(
        tf_->lookupTransform(topics_.world_frame, d.header.frame_id, d.header.stamp));
  } catch (const tf2::TransformException& e) {
    *error = where + ": no transform " + topics_.world_frame + " <- " + d.header.frame_id + ": " +
             e.what();
    return false;
  }
  if (!toStereoFrame(d, *images_[i], *infos_[i], T_world_camera, frame, error)) {
    *error = where + ": " + *error;
    return false;
  }
  return true;
}

}  // namespace stereo_fusion
