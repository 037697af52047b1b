#pragma once
// The node's frame input: a measurement (DisparityImage, or with input: depth a depth Image) +
// Image + CameraInfo synchronised (the first message of a stamp wins), queued (queue_size,
// drop_oldest), then on a worker thread the stamp gate, the wait for the camera pose in tf, the
// conversion (MessageConversions; depth through DepthToDisparity) and MappingSession::fuse().
// Images are subscribed through image_transport (~image_transport, ~depth_image_transport).
// Every frame that does not reach the map is counted in the session under its reason.
#include <image_transport/image_transport.h>
#include <image_transport/subscriber_filter.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <stereo_msgs/DisparityImage.h>
#include <tf2_ros/buffer.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>

#include "stereo_fusion/camera/DepthToDisparity.h"
#include "stereo_fusion/ros/NodeStats.h"
#include "stereo_fusion/ros/MeshPublisher.h"
#include "stereo_fusion/ros/RecentStamps.h"
#include "stereo_fusion/ros/RosParameters.h"
#include "stereo_fusion/ros/SequenceGaps.h"
#include "stereo_fusion/ros/UndecodableImages.h"
#include "stereo_fusion/session/MappingSession.h"
#include "stereo_fusion/session/OutputCadence.h"

namespace stereo_fusion {

class FrameInput {
 public:
  /// Throws std::invalid_argument (after logging it) when an image transport cannot be loaded.
  FrameInput(ros::NodeHandle& nh, ros::NodeHandle& private_nh, const NodeConfig& node,
             MappingSession* session, const tf2_ros::Buffer* tf, const OutputCadence* cadence,
             MeshPublisher* publisher, NodeStats* stats);
  /// Stops the worker (the frame in hand is finished or dropped first).
  ~FrameInput();

  /// The camera frame of the fused measurements ("" before the first).
  std::string cameraFrame() const;
  uint64_t disparitiesIn() const { return disparities_in_.load(); }
  uint64_t disparitiesMissed() const { return disparities_missed_.load(); }
  uint64_t framesMatched() const { return matched_.load(); }
  /// Disparities dropped on arrival, never handed to the synchroniser (each counted under its
  /// reason): what is neither matched nor refused is waiting, or was lost there.
  uint64_t disparitiesRefused() const { return disparities_refused_.load(); }
  uint64_t ignoredDuplicateParts() const { return ignored_duplicate_parts_.load(); }
  std::string topics() const;

 private:
  using DisparityMsg = stereo_msgs::DisparityImage;
  using ImageMsg = sensor_msgs::Image;
  using InfoMsg = sensor_msgs::CameraInfo;
  using ExactPolicy = message_filters::sync_policies::ExactTime<DisparityMsg, ImageMsg, InfoMsg>;
  using ApproxPolicy =
      message_filters::sync_policies::ApproximateTime<DisparityMsg, ImageMsg, InfoMsg>;
  using DepthExactPolicy = message_filters::sync_policies::ExactTime<ImageMsg, ImageMsg, InfoMsg>;
  using DepthApproxPolicy =
      message_filters::sync_policies::ApproximateTime<ImageMsg, ImageMsg, InfoMsg>;
  struct QueuedFrame {
    DisparityMsg::ConstPtr disparity;  ///< input: disparity
    ImageMsg::ConstPtr depth;          ///< input: depth
    const std_msgs::Header& header() const { return disparity ? disparity->header : depth->header; }
    ImageMsg::ConstPtr image;
    InfoMsg::ConstPtr info;
    FrameTicket ticket;  ///< taken on arrival
  };

  /// False if a message of `stamp` on that topic already waits in the synchroniser.
  bool passToSync(RecentStamps* stamps, const ros::Time& stamp) {
    std::lock_guard<std::mutex> lock(stamps_mutex_);
    return stamps->pass(stamp.toNSec());
  }
  /// Hands one message to whichever synchroniser runs (it calls onFrame when a set is complete).
  template <int I, typename M>
  void addToSync(const M& msg) {
    if constexpr (I == 0 && std::is_same_v<typename M::element_type, const DisparityMsg>) {
      if (exact_sync_) exact_sync_->template add<I>(msg);
      if (approx_sync_) approx_sync_->template add<I>(msg);
    } else if constexpr (I == 0) {
      if (depth_exact_sync_) depth_exact_sync_->template add<I>(msg);
      if (depth_approx_sync_) depth_approx_sync_->template add<I>(msg);
    } else {
      if (exact_sync_) exact_sync_->template add<I>(msg);
      if (approx_sync_) approx_sync_->template add<I>(msg);
      if (depth_exact_sync_) depth_exact_sync_->template add<I>(msg);
      if (depth_approx_sync_) depth_approx_sync_->template add<I>(msg);
    }
  }
  /// The checks every measurement (disparity or depth) passes on arrival; false: it was dropped
  /// and counted under its reason.
  bool admitMeasurement(const std_msgs::Header& header, const char* kind);
  /// Subscribes the image (and depth) through image_transport; throws std::invalid_argument.
  void subscribeImages(ros::NodeHandle& nh, ros::NodeHandle& private_nh);
  /// A compressed image (the colour image, or with `measurement` the depth image) that did not
  /// decode: its frame is counted as `undecodable image`, not left unmatched.
  void onUndecodable(bool measurement, const std::string& topic, const std_msgs::Header& header,
                     const std::string& error);
  void onFrame(const DisparityMsg::ConstPtr& d, const ImageMsg::ConstPtr& i,
               const InfoMsg::ConstPtr& c);
  void onDepthFrame(const ImageMsg::ConstPtr& depth, const ImageMsg::ConstPtr& i,
                    const InfoMsg::ConstPtr& c);
  void enqueue(QueuedFrame frame);
  void workerLoop();
  /// Fuses and publishes one frame; `publish_ms`: the publishing's time, if it was fused.
  void processFrame(const QueuedFrame& frame, double* publish_ms);
  /// Counts a frame dropped before the map under `reason` and says why (throttled).
  void drop(RejectReason reason, const std::string& why);
  /// Waits (wall time: a paused bag stops the ROS clock) up to tf_timeout_s for the camera pose.
  bool waitForPose(const std_msgs::Header& header, Eigen::Isometry3d* T_world_camera,
                   std::string* error);

  const NodeConfig& node_;
  MappingSession* session_;
  const tf2_ros::Buffer* tf_;
  const OutputCadence* cadence_;
  MeshPublisher* publisher_;
  NodeStats* stats_;

  std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<QueuedFrame> queue_;
  bool stopping_ = false;
  std::thread worker_;

  const DepthToDisparity depth_converter_;
  std::unique_ptr<image_transport::ImageTransport> transport_;
  message_filters::Subscriber<DisparityMsg> disparity_sub_;
  image_transport::SubscriberFilter depth_sub_;
  image_transport::SubscriberFilter image_sub_;
  message_filters::Subscriber<InfoMsg> info_sub_;
  /// The compressed transports' reports of images they could not decode (a report in progress
  /// finishes before the listening ends; ~FrameInput() unsubscribes before either is released).
  std::unique_ptr<UndecodableImages::Listening> undecodable_depth_, undecodable_image_;
  std::unique_ptr<message_filters::Synchronizer<ExactPolicy>> exact_sync_;
  std::unique_ptr<message_filters::Synchronizer<ApproxPolicy>> approx_sync_;
  std::unique_ptr<message_filters::Synchronizer<DepthExactPolicy>> depth_exact_sync_;
  std::unique_ptr<message_filters::Synchronizer<DepthApproxPolicy>> depth_approx_sync_;
  /// Stamps each topic passed to the synchroniser, not matched yet: the first message of a stamp
  /// wins.
  std::mutex stamps_mutex_;
  RecentStamps disparity_stamps_{1}, image_stamps_{1}, info_stamps_{1};
  SequenceGaps disparity_seq_;  // roscpp runs one subscription's callbacks one at a time: no lock

  std::atomic<uint64_t> disparities_in_{0}, disparities_missed_{0}, matched_{0},
      ignored_duplicate_parts_{0};
  std::atomic<uint64_t> disparities_refused_{0};
  /// True if `stamp` is the newest fused frame's, in the current map epoch.
  bool isNewestFusedStamp(const ros::Time& stamp) const;

  mutable std::mutex camera_frame_mutex_;  // guards the newest fused frame's camera frame and stamp
  std::string camera_frame_;
  std::pair<uint64_t, uint64_t> newest_fused_{0, 0};  // {epoch, stamp ns}
};

}  // namespace stereo_fusion
