#include "stereo_fusion/ros/CompressedSubscribers.h"

#include <pluginlib/class_list_macros.hpp>

#include <boost/make_shared.hpp>

#include "stereo_fusion/ros/CompressedImageDecoding.h"

namespace stereo_fusion {

namespace {

template <typename Decode>
void decodeAndPass(const sensor_msgs::CompressedImage& message,
                   const image_transport::SubscriberPlugin::Callback& user_cb, Decode decode,
                   const char* transport, uint64_t* undecodable) {
  const sensor_msgs::ImagePtr image = boost::make_shared<sensor_msgs::Image>();
  std::string error;
  if (!decode(message, image.get(), &error)) {
    ++*undecodable;
    ROS_ERROR_THROTTLE(5.0, "stereo_fusion: %s image stamped %.6f dropped (%llu so far): %s",
                       transport, message.header.stamp.toSec(),
                       static_cast<unsigned long long>(*undecodable), error.c_str());
    return;
  }
  user_cb(image);
}

}  // namespace

void CompressedImageSubscriber::internalCallback(
    const sensor_msgs::CompressedImage::ConstPtr& message, const Callback& user_cb) {
  decodeAndPass(*message, user_cb, decodeCompressedImage, "compressed", &undecodable_);
}

void CompressedDepthSubscriber::internalCallback(
    const sensor_msgs::CompressedImage::ConstPtr& message, const Callback& user_cb) {
  decodeAndPass(*message, user_cb, decodeCompressedDepth, "compressedDepth", &undecodable_);
}

}  // namespace stereo_fusion

PLUGINLIB_EXPORT_CLASS(stereo_fusion::CompressedImageSubscriber, image_transport::SubscriberPlugin)
PLUGINLIB_EXPORT_CLASS(stereo_fusion::CompressedDepthSubscriber, image_transport::SubscriberPlugin)
