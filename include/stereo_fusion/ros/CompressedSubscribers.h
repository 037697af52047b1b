#pragma once
// image_transport subscriber plugins for the `compressed` and `compressedDepth` transports
// (image_transport_plugins' formats, decoded by CompressedImageDecoding), exported in
// image_transport_plugins.xml: Debian ships image_transport with the raw transport only. Where
// image_transport_plugins is installed, pluginlib takes the first of the two it finds; both
// decode the same messages. A message that does not decode is dropped here and reported to the
// topic's subscriber (UndecodableImages: the nodelet counts its frame as `dropped: undecodable
// image` and logs why); with no such listener it is logged here (throttled).

#include <image_transport/simple_subscriber_plugin.h>
#include <sensor_msgs/CompressedImage.h>

#include <atomic>
#include <cstdint>

namespace stereo_fusion {

class CompressedImageSubscriber
    : public image_transport::SimpleSubscriberPlugin<sensor_msgs::CompressedImage> {
 public:
  std::string getTransportName() const override { return "compressed"; }

 protected:
  void internalCallback(const sensor_msgs::CompressedImage::ConstPtr& message,
                        const Callback& user_cb) override;

 private:
  uint64_t undecodable_ = 0;  // one subscription's callbacks run one at a time
};

class CompressedDepthSubscriber
    : public image_transport::SimpleSubscriberPlugin<sensor_msgs::CompressedImage> {
 public:
  std::string getTransportName() const override { return "compressedDepth"; }

 protected:
  void internalCallback(const sensor_msgs::CompressedImage::ConstPtr& message,
                        const Callback& user_cb) override;

 private:
  uint64_t undecodable_ = 0;
};

}  // namespace stereo_fusion
