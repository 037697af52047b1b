#pragma once
// Where image_transport's compressed subscriber plugins (CompressedSubscribers) report an image
// they could not decode, so that the subscriber counts it under its true reason. pluginlib
// creates the plugins inside image_transport, out of the subscriber's reach: the subscriber
// (FrameInput) listens here by topic instead. A shared library of its own
// (libstereo_fusion_decode_reports), linked by the plugins' library and by the nodelet, so that
// both see the one registry of their process.

#include <std_msgs/Header.h>

#include <functional>
#include <memory>
#include <string>

namespace stereo_fusion {

class UndecodableImages {
 public:
  /// Called with the dropped message's header and why it did not decode.
  using Listener = std::function<void(const std_msgs::Header& header, const std::string& error)>;

  /// Stops the listening when destroyed (after a report in progress has returned).
  class Listening {
   public:
    explicit Listening(uint64_t id) : id_(id) {}
    ~Listening();
    Listening(const Listening&) = delete;
    Listening& operator=(const Listening&) = delete;

   private:
    uint64_t id_;
  };

  /// `listener` hears of every image on `transport_topic` (the topic the transport subscribes,
  /// resolved: "<base topic>/compressed", "<base topic>/compressedDepth") that does not decode,
  /// on that subscription's callback thread, while the returned handle lives.
  static std::unique_ptr<Listening> listen(const std::string& transport_topic, Listener listener);

  /// Tells the listeners of `transport_topic`; false when none listens (the caller logs then).
  static bool report(const std::string& transport_topic, const std_msgs::Header& header,
                     const std::string& error);
};

}  // namespace stereo_fusion
