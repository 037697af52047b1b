#include "stereo_fusion/ros/FrameInput.h"

#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>

#include "stereo_fusion/ros/MessageConversions.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

FrameInput::FrameInput(ros::NodeHandle& nh, ros::NodeHandle& private_nh, const NodeConfig& node,
                       MappingSession* session, const tf2_ros::Buffer* tf,
                       const OutputCadence* cadence, MeshPublisher* publisher, NodeStats* stats)
    : node_(node),
      session_(session),
      tf_(tf),
      cadence_(cadence),
      publisher_(publisher),
      stats_(stats),
      depth_converter_(DepthConversionConfig{node.depth_baseline_m}) {
  // The synchroniser is fed by hand so that the first message of a stamp on each topic wins: it
  // would let a second one replace the first while the set is incomplete (see RecentStamps).
  const size_t stamp_window = static_cast<size_t>(std::max(8, 2 * node_.sync_queue_size));
  disparity_stamps_ = RecentStamps(stamp_window);
  image_stamps_ = RecentStamps(stamp_window);
  info_stamps_ = RecentStamps(stamp_window);
  const bool depth = node_.input == InputMode::kDepth;
  if (depth && node_.approximate_sync) {
    depth_approx_sync_ = std::make_unique<message_filters::Synchronizer<DepthApproxPolicy>>(
        DepthApproxPolicy(node_.sync_queue_size));
    depth_approx_sync_->registerCallback(&FrameInput::onDepthFrame, this);
  } else if (depth) {
    depth_exact_sync_ = std::make_unique<message_filters::Synchronizer<DepthExactPolicy>>(
        DepthExactPolicy(node_.sync_queue_size));
    depth_exact_sync_->registerCallback(&FrameInput::onDepthFrame, this);
  } else if (node_.approximate_sync) {
    approx_sync_ = std::make_unique<message_filters::Synchronizer<ApproxPolicy>>(
        ApproxPolicy(node_.sync_queue_size));
    approx_sync_->registerCallback(&FrameInput::onFrame, this);
  } else {
    exact_sync_ = std::make_unique<message_filters::Synchronizer<ExactPolicy>>(
        ExactPolicy(node_.sync_queue_size));
    exact_sync_->registerCallback(&FrameInput::onFrame, this);
  }
  // Callbacks first, subscriptions after: a message arriving in between would reach no callback
  // and be lost uncounted (a player that starts on the first subscription sends one at once).
  disparity_sub_.registerCallback([this](const DisparityMsg::ConstPtr& disparity) {
    if (admitMeasurement(disparity->header, "disparity")) addToSync<0>(disparity);
  });
  depth_sub_.registerCallback([this](const ImageMsg::ConstPtr& depth) {
    if (admitMeasurement(depth->header, "depth image")) addToSync<0>(depth);
  });
  image_sub_.registerCallback([this](const ImageMsg::ConstPtr& image) {
    if (passToSync(&image_stamps_, image->header.stamp))
      addToSync<1>(image);
    else
      ++ignored_duplicate_parts_;
  });
  info_sub_.registerCallback([this](const InfoMsg::ConstPtr& info) {
    if (passToSync(&info_stamps_, info->header.stamp))
      addToSync<2>(info);
    else
      ++ignored_duplicate_parts_;
  });
  worker_ = std::thread([this] { workerLoop(); });
  try {
    subscribeImages(nh, private_nh);
  } catch (...) {
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      stopping_ = true;
    }
    queue_cv_.notify_all();
    worker_.join();
    throw;
  }
  if (!depth) disparity_sub_.subscribe(nh, "disparity", 5);
  info_sub_.subscribe(nh, "camera_info", 5);
}

void FrameInput::subscribeImages(ros::NodeHandle& nh, ros::NodeHandle& private_nh) {
  transport_ = std::make_unique<image_transport::ImageTransport>(nh);
  const auto subscribe = [&](image_transport::SubscriberFilter* sub, const std::string& topic,
                             const std::string& transport, const char* parameter) {
    try {
      // The remapped name: a transport other than raw subscribes to <base>/<transport>, which
      // a remapping of the base name (the nodelet's, or the launch file's) does not reach.
      sub->subscribe(
          *transport_, nh.resolveName(topic), 5,
          image_transport::TransportHints(transport, ros::TransportHints(), private_nh, parameter));
    } catch (const std::exception& e) {  // image_transport::TransportLoadException, pluginlib's
      std::string loadable;
      for (const std::string& name : transport_->getLoadableTransports())
        loadable += (loadable.empty() ? "" : ", ") + name;
      const std::string why = std::string(parameter) + " '" + transport + "' for '" +
                              nh.resolveName(topic) + "' cannot be loaded (" + e.what() +
                              "); loadable here: " + loadable;
      ROS_FATAL("stereo_fusion: %s", why.c_str());
      throw std::invalid_argument(why);
    }
  };
  // The listening first: an image that fails at once is counted too. The key is the topic the
  // transport subscribes (image_transport's <base>/<transport>), as its plugin reports it.
  const auto listen = [&](const std::string& topic, const std::string& transport,
                          bool measurement) {
    const std::string transport_topic = nh.resolveName(topic) + "/" + transport;
    return UndecodableImages::listen(
        transport_topic, [this, measurement, transport_topic](const std_msgs::Header& header,
                                                              const std::string& error) {
          onUndecodable(measurement, transport_topic, header, error);
        });
  };
  if (node_.input == InputMode::kDepth) {
    undecodable_depth_ = listen("depth", node_.depth_image_transport, true);
    subscribe(&depth_sub_, "depth", node_.depth_image_transport, "depth_image_transport");
  }
  undecodable_image_ = listen("image", node_.image_transport, false);
  subscribe(&image_sub_, "image", node_.image_transport, "image_transport");
}

void FrameInput::onUndecodable(bool measurement, const std::string& topic,
                               const std_msgs::Header& header, const std::string& error) {
  if (measurement) {  // the depth image: received, as admitMeasurement() would have counted it
    ++disparities_in_;
    // On the depth subscription's callback (the transport's): never beside admitMeasurement().
    disparities_missed_ += disparity_seq_.next(header.seq);
  }
  // The measurement of this frame (the depth image itself, or the disparity that arrives with
  // the colour image) can never be matched: refused here, so it is not also counted as
  // "not synchronised".
  ++disparities_refused_;
  drop(RejectReason::kUndecodableImage,
       std::string(measurement ? "the depth image" : "the image") + " on " + topic + " stamped " +
           std::to_string(header.stamp.toSec()) + " does not decode: " + error);
}

bool FrameInput::admitMeasurement(const std_msgs::Header& header, const char* kind) {
  ++disparities_in_;
  disparities_missed_ += disparity_seq_.next(header.seq);
  // Stamped 0, it could never be fused (its pose cannot be looked up): counted as what it is
  // at once, rather than as unsynchronised when its image and camera_info carry real stamps.
  if (header.stamp.isZero()) {
    ++disparities_refused_;
    drop(RejectReason::kBadStamp,
         std::string("a ") + kind + " stamped 0 (no time: its pose cannot be looked up)");
    return false;
  }
  // The stamp of the newest fused frame: the frame gate would refuse it as a duplicate
  // whatever else came with it, so it is counted as that now, not left unmatched.
  if (isNewestFusedStamp(header.stamp)) {
    ++disparities_refused_;
    drop(RejectReason::kDuplicateTimestamp, std::string("a ") + kind + " stamped " +
                                                std::to_string(header.stamp.toSec()) +
                                                ", the stamp of the newest fused frame");
    return false;
  }
  if (!passToSync(&disparity_stamps_, header.stamp)) {
    ++disparities_refused_;
    drop(RejectReason::kSyncDuplicate,
         std::string("a second ") + kind + " stamped " + std::to_string(header.stamp.toSec()) +
             " arrived before its frame was matched; the first is kept");
    return false;
  }
  return true;
}

FrameInput::~FrameInput() {
  // The subscribers go first: no callback may queue a frame for a worker that has stopped.
  disparity_sub_.unsubscribe();
  depth_sub_.unsubscribe();
  image_sub_.unsubscribe();
  info_sub_.unsubscribe();
  // Then the decode reports, before the counters and sequences they update are destroyed.
  undecodable_depth_.reset();
  undecodable_image_.reset();
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stopping_ = true;
  }
  queue_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

std::string FrameInput::topics() const {
  const std::string measurement =
      node_.input == InputMode::kDepth
          ? depth_sub_.getTopic() + " (depth, " + node_.depth_image_transport + ")"
          : disparity_sub_.getTopic();
  return measurement + " + " + image_sub_.getTopic() + " (" + node_.image_transport + ") + " +
         info_sub_.getTopic();
}

bool FrameInput::isNewestFusedStamp(const ros::Time& stamp) const {
  std::lock_guard<std::mutex> lock(camera_frame_mutex_);
  return newest_fused_.first == session_->epoch() && newest_fused_.second == stamp.toNSec() &&
         !stamp.isZero();
}

std::string FrameInput::cameraFrame() const {
  std::lock_guard<std::mutex> lock(camera_frame_mutex_);
  return camera_frame_;
}

void FrameInput::drop(RejectReason reason, const std::string& why) {
  session_->countDrop(reason);
  ROS_WARN_THROTTLE(5.0, "stereo_fusion: frame dropped (%s, %llu so far): %s",
                    rejectReasonName(reason),
                    static_cast<unsigned long long>(session_->drops()[reason]), why.c_str());
}

void FrameInput::onFrame(const DisparityMsg::ConstPtr& d, const ImageMsg::ConstPtr& i,
                         const InfoMsg::ConstPtr& c) {
  enqueue({d, nullptr, i, c, {}});
}

void FrameInput::onDepthFrame(const ImageMsg::ConstPtr& depth, const ImageMsg::ConstPtr& i,
                              const InfoMsg::ConstPtr& c) {
  enqueue({nullptr, depth, i, c, {}});
}

void FrameInput::enqueue(QueuedFrame frame) {
  ++matched_;
  {
    std::lock_guard<std::mutex> lock(stamps_mutex_);
    disparity_stamps_.forget(frame.header().stamp.toNSec());
    image_stamps_.forget(frame.image->header.stamp.toNSec());
    info_stamps_.forget(frame.info->header.stamp.toNSec());
  }
  frame.ticket = session_->arrive();
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    if (queue_.size() >= static_cast<size_t>(node_.queue_size)) {
      drop(RejectReason::kQueueFull, "frame queue full (" + std::to_string(node_.queue_size) +
                                         "), dropping the " +
                                         (node_.drop_oldest ? "oldest" : "newest") + " frame");
      if (!node_.drop_oldest) return;
      queue_.pop_front();
    }
    queue_.push_back(std::move(frame));
  }
  queue_cv_.notify_one();
}

void FrameInput::workerLoop() {
  while (true) {
    QueuedFrame frame;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      queue_cv_.wait_for(lock, std::chrono::milliseconds(100),
                         [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      if (queue_.empty()) {
        lock.unlock();
        publisher_->publishPending(ros::Time(0), false);  // flush a rate-limited update
        continue;
      }
      frame = queue_.front();
      queue_.pop_front();
    }
    try {
      const Timer worker;
      double publish_ms = -1.0;  // set once the frame is fused
      processFrame(frame, &publish_ms);
      if (publish_ms >= 0.0)
        stats_->recordWorkerFrame(worker.elapsedMs(), publish_ms);
      else  // dropped or rejected: what earlier frames changed still goes out when due
        publisher_->publishPending(ros::Time(0), false);
    } catch (const std::exception& e) {
      // One bad frame (or an allocation failure) must not take the nodelet manager down.
      drop(RejectReason::kError, std::string("an error: ") + e.what());
    }
  }
}

bool FrameInput::waitForPose(const std_msgs::Header& header, Eigen::Isometry3d* T_world_camera,
                             std::string* error) {
  // Wall time: under simulated time a paused or finished bag stops the ROS clock, and a
  // ROS-time timeout would then never expire. Shutdown interrupts the wait.
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(node_.tf_timeout_s);
  while (true) {
    error->clear();
    try {
      if (tf_->canTransform(node_.world_frame, header.frame_id, header.stamp, error)) break;
    } catch (const std::exception& e) {  // tf's time arithmetic throws on absurd stamps
      *error = std::string("tf cannot look up this stamp: ") + e.what();
      return false;
    }
    if (ros::WallTime::now() >= deadline) return false;
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      if (stopping_) return false;
    }
    ros::WallDuration(0.005).sleep();
  }
  try {
    *T_world_camera = tf2::transformToEigen(
        tf_->lookupTransform(node_.world_frame, header.frame_id, header.stamp));
  } catch (const std::exception& e) {  // tf2::TransformException, or its time arithmetic
    *error = e.what();
    return false;
  }
  return true;
}

void FrameInput::processFrame(const QueuedFrame& f, double* publish_ms) {
  const std_msgs::Header& header = f.header();
  if (!session_->isCurrent(f.ticket))  // a reset or load_map came while it waited in the queue
    return session_->countDrop(RejectReason::kSuperseded);
  // A stamp of 0 would make tf return its latest pose, whatever time the image is from; a stamp
  // far ahead of the clock is a broken driver clock. Neither may reach the map.
  const ros::Time now = ros::Time::now();
  if (header.stamp.isZero())
    return drop(RejectReason::kBadStamp, "stamped 0 (no time: its pose cannot be looked up)");
  if (stampAheadOfClock(header.stamp, now, node_.max_stamp_ahead_s))
    return drop(RejectReason::kBadStamp,
                "stamped " + std::to_string(header.stamp.toSec()) +
                    " s, ahead of the clock by more than max_stamp_ahead_s");
  Eigen::Isometry3d T_world_camera;
  std::string error;
  if (!waitForPose(header, &T_world_camera, &error)) {
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      if (stopping_) return;
    }
    return drop(RejectReason::kTfTimeout, "no transform " + node_.world_frame + " <- " +
                                              header.frame_id + " at " +
                                              std::to_string(header.stamp.toSec()) + " within " +
                                              std::to_string(node_.tf_timeout_s) + " s: " + error);
  }
  StereoFrame frame;
  const bool converted =
      f.disparity ? toStereoFrame(*f.disparity, *f.image, *f.info, T_world_camera, &frame, &error)
                  : depthToStereoFrame(*f.depth, *f.image, *f.info, depth_converter_,
                                       T_world_camera, &frame, &error);
  if (!converted) return drop(RejectReason::kInvalidFrame, "bad input: " + error);
  // Deferred, the mesh is brought up to date when it is published (MeshPublisher::
  // publishPending()), at most mesh_publish_rate_hz (OutputCadence).
  const MappingSession::FrameOutcome out =
      session_->fuse(frame, f.ticket, cadence_->meshTiming(session_->framesFused() + 1));
  if (out.reason != RejectReason::kNone) {
    ROS_ERROR_THROTTLE(
        5.0, "stereo_fusion: frame rejected (%s, %llu so far): %s", rejectReasonName(out.reason),
        static_cast<unsigned long long>(session_->drops()[out.reason]), out.error.c_str());
    return;
  }
  const IntegrationResult& r = out.result;
  const FrameStats frame_stats = frameStats(r, true);
  const StageTimings& t = frame_stats.timings;
  // Free-space carving counts as fusion: it is the frame's update of the map.
  stats_->recordFrame(t.lookup_ms, t.fusion_ms + t.carve_ms, t.stagesMs());
  if (frame_stats.mesh_pass_ran) stats_->recordMeshPass(t.meshing_ms, t.texture_ms);
  {
    std::lock_guard<std::mutex> lock(camera_frame_mutex_);
    camera_frame_ = header.frame_id;
    newest_fused_ = {f.ticket.epoch, header.stamp.toNSec()};
  }
  double measured_noise_px = 0.0;
  uint64_t frames_fused = 0;
  std::string noise_warning;
  session_->read([&](const Mapper& mapper) {
    publisher_->frameFusedLocked(frame, header);
    measured_noise_px = mapper.measuredDisparityNoisePx();
    frames_fused = mapper.framesIntegrated();
    noise_warning = mapper.disparityNoiseWarning();
  });
  stats_->disparity_noise_measured_px = measured_noise_px;
  // Once, when the estimate has settled (a full window of frames).
  if (!noise_warning.empty() && frames_fused >= Mapper::kNoiseFrames &&
      !stats_->disparity_noise_warned.exchange(true))
    ROS_WARN("stereo_fusion: %s", noise_warning.c_str());
  if (r.reanchored) {  // counted by the session
    ROS_WARN("stereo_fusion: %s", r.note.c_str());
  }
  bool frames_waiting;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    frames_waiting = !queue_.empty();
  }
  const Timer publishing;
  publisher_->publishPending(header.stamp, false, frames_waiting);
  *publish_ms = publishing.elapsedMs();
}

}  // namespace stereo_fusion
