#include "stereo_fusion/ros/BagSequence.h"

#include <ros/exception.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <stereo_msgs/DisparityImage.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <map>
#include <mutex>
#include <optional>
#include <vector>

#include "stereo_fusion/ros/MessageConversions.h"

namespace stereo_fusion {
namespace {

/// The stamp of a message that starts with a std_msgs/Header (DisparityImage, Image, CameraInfo),
/// read without the rest of it: instantiating this from a bag reads the message's record but
/// copies none of its image. Its MD5 sum "*" matches any type; callers check the type first.
struct HeaderStamp {
  ros::Time stamp;
};

}  // namespace
}  // namespace stereo_fusion

namespace ros {
namespace message_traits {
template <>
struct MD5Sum<stereo_fusion::HeaderStamp> {
  static const char* value() { return "*"; }
  static const char* value(const stereo_fusion::HeaderStamp&) { return value(); }
};
template <>
struct DataType<stereo_fusion::HeaderStamp> {
  static const char* value() { return "*"; }
  static const char* value(const stereo_fusion::HeaderStamp&) { return value(); }
};
template <>
struct Definition<stereo_fusion::HeaderStamp> {
  static const char* value() { return ""; }
  static const char* value(const stereo_fusion::HeaderStamp&) { return value(); }
};
}  // namespace message_traits
namespace serialization {
template <>
struct Serializer<stereo_fusion::HeaderStamp> {
  template <typename Stream>
  static void read(Stream& stream, stereo_fusion::HeaderStamp& m) {
    uint32_t seq = 0;  // std_msgs/Header: seq, stamp, frame_id
    stream.next(seq);
    stream.next(m.stamp);
  }
};
}  // namespace serialization
}  // namespace ros

namespace stereo_fusion {

/// Where each frame's messages lie in the open bag, and the transforms.
struct BagSequence::Index {
  /// One frame: its DisparityImage, and the Image with the same stamp and the CameraInfo it pairs
  /// with (indices into `messages`; none when the bag has none).
  struct Frame {
    size_t disparity = 0;
    std::optional<size_t> image, info;
  };
  BagTopics topics;
  std::unique_ptr<tf2::BufferCore> tf;
  /// rosbag::Bag reads through buffers of its own: one reader at a time.
  mutable std::mutex bag_mutex;
  rosbag::Bag bag;  // open for the sequence's lifetime; `messages` point into it
  std::vector<rosbag::MessageInstance> messages;  // a message's place (chunk, offset), no data
  std::vector<Frame> frames;
};

BagSequence::BagSequence() : index_(std::make_unique<Index>()) {}
BagSequence::~BagSequence() = default;

size_t BagSequence::size() const { return index_->frames.size(); }

std::unique_ptr<BagSequence> BagSequence::open(const std::string& path, const BagTopics& topics,
                                               std::string* error) {
  auto seq = std::unique_ptr<BagSequence>(new BagSequence());
  Index& index = *seq->index_;
  index.topics = topics;
  try {
    index.bag.open(path, rosbag::bagmode::Read);
    rosbag::View all(index.bag);
    if (all.size() == 0) {
      *error = path + ": the bag holds no messages";
      return nullptr;
    }
    // Keep every transform of the recording: frames are looked up after reading it all.
    const ros::Duration span = all.getEndTime() - all.getBeginTime() + ros::Duration(60.0);
    index.tf = std::make_unique<tf2::BufferCore>(span);
    // Header stamps with the message's place in `index.messages`, in the bag's order.
    std::vector<std::pair<ros::Time, size_t>> disparities, infos;
    std::map<ros::Time, size_t> images;  // by stamp: the last one of a stamp wins
    auto stampOf = [](const rosbag::MessageInstance& m) -> std::optional<ros::Time> {
      const auto header = m.instantiate<HeaderStamp>();
      if (!header) return std::nullopt;
      return header->stamp;
    };
    rosbag::View view(index.bag, rosbag::TopicQuery({topics.disparity, topics.image,
                                                     topics.camera_info, "/tf", "/tf_static"}));
    for (const rosbag::MessageInstance& m : view) {
      if (m.getTopic() == "/tf" || m.getTopic() == "/tf_static") {
        if (auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
          const bool is_static = m.getTopic() == "/tf_static";
          for (const auto& t : tf->transforms) index.tf->setTransform(t, "bag", is_static);
        }
        continue;
      }
      std::vector<std::pair<ros::Time, size_t>>* list = nullptr;
      std::optional<ros::Time> stamp;
      if (m.getTopic() == topics.disparity) {
        if (!m.isType<stereo_msgs::DisparityImage>() || !(stamp = stampOf(m))) continue;
        list = &disparities;
      } else if (m.getTopic() == topics.image) {
        if (!m.isType<sensor_msgs::Image>() || !(stamp = stampOf(m))) continue;
        images[*stamp] = index.messages.size();
      } else if (m.getTopic() == topics.camera_info) {
        if (!m.isType<sensor_msgs::CameraInfo>() || !(stamp = stampOf(m))) continue;
        list = &infos;
      } else {
        continue;
      }
      if (list) list->emplace_back(*stamp, index.messages.size());
      index.messages.push_back(m);
    }
    if (disparities.empty()) {
      *error = path + ": no stereo_msgs/DisparityImage on topic " + topics.disparity;
      return nullptr;
    }
    // Camera info rarely changes: a frame takes the latest one (in the bag's order) not after
    // it, or the first one. `latest[k]`: the latest of the k + 1 earliest-stamped infos.
    std::vector<std::pair<ros::Time, size_t>> by_stamp = infos;
    std::stable_sort(by_stamp.begin(), by_stamp.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<size_t> latest(by_stamp.size());
    for (size_t k = 0; k < by_stamp.size(); ++k)
      latest[k] = std::max(by_stamp[k].second, k > 0 ? latest[k - 1] : 0);
    for (const auto& [stamp, message] : disparities) {
      Index::Frame frame;
      frame.disparity = message;
      if (const auto im = images.find(stamp); im != images.end()) frame.image = im->second;
      if (!infos.empty()) {
        const auto not_after = std::upper_bound(
            by_stamp.begin(), by_stamp.end(), stamp,
            [](const ros::Time& t, const std::pair<ros::Time, size_t>& e) { return t < e.first; });
        const size_t k = static_cast<size_t>(not_after - by_stamp.begin());
        frame.info = k > 0 ? latest[k - 1] : infos.front().second;
      }
      index.frames.push_back(frame);
    }
  } catch (const ros::Exception& e) {  // rosbag::BagException, or a message cut short
    *error = path + ": cannot read the bag: " + e.what();
    return nullptr;
  }
  return seq;
}

bool BagSequence::load(size_t i, StereoFrame* frame, std::string* error) const {
  const Index& index = *index_;
  if (i >= index.frames.size()) {
    *error = "frame " + std::to_string(i) + " is out of range";
    return false;
  }
  const Index::Frame& f = index.frames[i];
  stereo_msgs::DisparityImage::ConstPtr disparity;
  sensor_msgs::Image::ConstPtr image;
  sensor_msgs::CameraInfo::ConstPtr info;
  try {
    std::lock_guard<std::mutex> lock(index.bag_mutex);
    disparity = index.messages[f.disparity].instantiate<stereo_msgs::DisparityImage>();
    if (f.image) image = index.messages[*f.image].instantiate<sensor_msgs::Image>();
    if (f.info) info = index.messages[*f.info].instantiate<sensor_msgs::CameraInfo>();
  } catch (const ros::Exception& e) {  // the file changed since open(), or a message cut short
    *error = "frame " + std::to_string(i) + ": cannot read the bag: " + e.what();
    return false;
  }
  if (!disparity) {  // open() checked the type: only a bag changed since can get here
    *error = "frame " + std::to_string(i) + ": cannot read its DisparityImage";
    return false;
  }
  const auto& d = *disparity;
  const std::string where =
      "frame " + std::to_string(i) + " (stamp " + std::to_string(d.header.stamp.toSec()) + ")";
  if (!image) {
    *error = where + ": no image on " + index.topics.image + " with the same stamp";
    return false;
  }
  if (!info) {
    *error = where + ": no CameraInfo on " + index.topics.camera_info;
    return false;
  }
  Eigen::Isometry3d T_world_camera;
  try {
    T_world_camera = tf2::transformToEigen(
        index.tf->lookupTransform(index.topics.world_frame, d.header.frame_id, d.header.stamp));
  } catch (const tf2::TransformException& e) {
    *error = where + ": no transform " + index.topics.world_frame + " <- " + d.header.frame_id +
             ": " + e.what();
    return false;
  }
  if (!toStereoFrame(d, *image, *info, T_world_camera, frame, error)) {
    *error = where + ": " + *error;
    return false;
  }
  return true;
}

}  // namespace stereo_fusion
