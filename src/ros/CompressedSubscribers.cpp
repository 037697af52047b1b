#include "stereo_fusion/ros/CompressedSubscribers.h"

#include <pluginlib/class_list_macros.hpp>

#include <boost/make_shared.hpp>

#include "stereo_fusion/ros/CompressedImageDecoding.h"
#include "stereo_fusion/ros/UndecodableImages.h"

namespace stereo_fusion {

namespace {

template <typename Decode>
void decodeAndPass(const sensor_msgs::CompressedImage& message,
                   const image_transport::SubscriberPlugin::Callback& user_cb, Decode decode,
                   const std::string& topic, uint64_t* undecodable) {
  const sensor_msgs::ImagePtr image = boost::make_shared<sensor_msgs::Image>();
  std::string error;
  if (!decode(message, image.get(), &error)) {
    ++*undecodable;
    // The subscriber (the nodelet) counts and logs it under its reason; anyone else is told here.
    if (!UndecodableImages::report(topic, message.header, error))
      ROS_ERROR_THROTTLE(5.0, "stereo_fusion: image on %s stamped %.6f dropped (%llu so far): %s",
                         topic.c_str(), message.header.stamp.toSec(),
                         static_cast<unsigned long long>(*undecodable), error.c_str());
    return;
  }
  user_cb(image);
}

}  // namespace

void CompressedImageSubscriber::internalCallback(
    const sensor_msgs::CompressedImage::ConstPtr& message, const Callback& user_cb) {
  decodeAndPass(*message, user_cb, decodeCompressedImage, getTopic(), &undecodable_);
}

void CompressedDepthSubscriber::internalCallback(
    const sensor_msgs::CompressedImage::ConstPtr& message, const Callback& user_cb) {
  decodeAndPass(*message, user_cb, decodeCompressedDepth, getTopic(), &undecodable_);
}

}  // namespace stereo_fusion

PLUGINLIB_EXPORT_CLASS(stereo_fusion::CompressedImageSubscriber, image_transport::SubscriberPlugin)
PLUGINLIB_EXPORT_CLASS(stereo_fusion::CompressedDepthSubscriber, image_transport::SubscriberPlugin)
