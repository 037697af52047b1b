#pragma once
// Shared by the ROS integration tests: frames as the nodelet's input messages, reading the
// nodelet's counters from /diagnostics, and the main() every rostest gtest node needs.

#include <gtest/gtest.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>
#include <std_srvs/SetBool.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/transform_broadcaster.h>

#include "stereo_fusion/ros/MessageConversions.h"

#include <algorithm>
#include <map>
#include <mutex>
#include <vector>
#include <string>
#include <utility>

namespace stereo_fusion::test {

/// One frame as the nodelet's input.
struct FrameMessages {
  std_msgs::Header header;
  stereo_msgs::DisparityImage disparity;
  sensor_msgs::Image image;
  sensor_msgs::CameraInfo info;
};

/// `frame` as messages stamped `stamp` (now when zero) in `frame_id`; with `tf`, its pose
/// map (the nodelet's default world_frame) → frame_id is broadcast first. Publishing (and any delay
/// before it) is the caller's.
inline FrameMessages frameMessages(const StereoFrame& frame, tf2_ros::TransformBroadcaster* tf,
                                   const std::string& frame_id = "left_optical",
                                   ros::Time stamp = ros::Time()) {
  FrameMessages m;
  m.header.stamp = stamp.isZero() ? ros::Time::now() : stamp;
  m.header.frame_id = frame_id;
  if (tf) tf->sendTransform(toTransform(frame.T_world_camera, "map", m.header));
  toMessages(frame, m.header, 128.0f, &m.disparity, &m.image, &m.info);
  return m;
}

/// The latest key/value pairs of the "fusion" diagnostics status.
class DiagnosticsWatcher {
 public:
  /// Watches the statuses whose name contains `name_part` (the fusion nodelet's by default).
  explicit DiagnosticsWatcher(std::string name_part = "fusion") : name_part_(std::move(name_part)) {
    sub_ = ros::NodeHandle().subscribe("/diagnostics", 10, &DiagnosticsWatcher::onMessage, this);
  }
  /// The spinner threads may be in onMessage while a test ends: shutdown() waits for that
  /// callback before the members it reads are destroyed (TSan saw the map freed under it).
  ~DiagnosticsWatcher() { sub_.shutdown(); }
  DiagnosticsWatcher(const DiagnosticsWatcher&) = delete;
  DiagnosticsWatcher& operator=(const DiagnosticsWatcher&) = delete;

  /// Waits for the next report after this call. Counters only grow, so values read after it are
  /// at least what the node had counted when this was called: a stale, lower reading taken as
  /// a baseline would make later "count ≥ baseline + n" waits pass too early.
  bool waitForNextReport(double timeout_s) {
    uint64_t seen;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      seen = reports_;
    }
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
    while (ros::ok() && ros::WallTime::now() < end) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (reports_ > seen) return true;
      }
      ros::WallDuration(0.02).sleep();
    }
    return false;
  }

  /// The sum of every counter whose key starts with "dropped: " (each frame the node received
  /// and did not fuse is in exactly one); 0 before the first report.
  long droppedTotal() {
    std::lock_guard<std::mutex> lock(mutex_);
    long sum = 0;
    for (const auto& kv : values_)
      if (kv.first.rfind("dropped: ", 0) == 0) sum += std::max(0L, std::stol(kv.second));
    return sum;
  }

  /// The value of `key` as an integer, or -1 when it has not been reported yet.
  long value(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = values_.find(key);
    return it == values_.end() ? -1 : std::stol(it->second);
  }

 private:
  void onMessage(const diagnostic_msgs::DiagnosticArray::ConstPtr& a) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++reports_;
    for (const auto& status : a->status)
      if (status.name.find(name_part_) != std::string::npos)
        for (const auto& kv : status.values) values_[kv.key] = kv.value;
  }
  std::string name_part_;
  ros::Subscriber sub_;
  std::mutex mutex_;
  std::map<std::string, std::string> values_;
  uint64_t reports_ = 0;
};

/// Polls `done` every 50 ms (callbacks run on the spinner threads) until it holds or
/// `timeout_s` of wall time pass.
template <typename F>
bool waitFor(F&& done, double timeout_s) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (done()) return true;
    ros::WallDuration(0.05).sleep();
  }
  return done();
}

/// Waits until a node (the fusion nodelet's tf listener) is connected to this process's /tf
/// publication, which a TransformBroadcaster shares: a transform sent before that connection
/// is up is lost, and its frame then dropped for want of tf, however long the test waits. The
/// broadcaster must exist before this call and outlive it: the publication lives only while
/// some publisher of /tf in the process does.
inline bool waitForTfSubscriber(double timeout_s) {
  const ros::Publisher tf_pub = ros::NodeHandle().advertise<tf2_msgs::TFMessage>("/tf", 100);
  return waitFor([&] { return tf_pub.getNumSubscribers() > 0; }, timeout_s);
}

/// Starts the bag of a replay.launch run with start_paused:=true once the fusion nodelet runs:
/// two reports of its diagnostics (its callback queue has been running for a second), then
/// /player/pause_playback(false). With wait_for_subscribers:=true the player also waits for a
/// subscriber on each of its topics, so no frame leaves before the nodelet listens.
inline bool startPausedPlayer(DiagnosticsWatcher& diagnostics, double timeout_s = 60.0) {
  if (!diagnostics.waitForNextReport(timeout_s) || !diagnostics.waitForNextReport(timeout_s))
    return false;
  if (!ros::service::waitForService("/player/pause_playback", ros::Duration(timeout_s)))
    return false;
  std_srvs::SetBool play;
  play.request.data = false;
  return ros::service::call("/player/pause_playback", play);
}

/// gtest + a ROS node with a two-thread spinner, then every test.
/// Which SubMesh fields expectSameSubmeshes() compares besides positions and triangles.
enum SubmeshFields { kGeometry = 0, kWithColors = 1, kWithNormals = 2 };

/// Expects `got` (key → SubMesh) to hold exactly the blocks of `want`, with bit-identical
/// positions and triangles (and colours / normals when asked).
template <typename MapA, typename MapB>
void expectSameSubmeshes(const MapA& got, const MapB& want, int fields = kGeometry) {
  ASSERT_EQ(got.size(), want.size());
  for (const auto& [key, sub] : want) {
    auto it = got.find(key);
    ASSERT_NE(it, got.end()) << key;
    EXPECT_EQ(it->second.positions, sub.positions) << key;
    EXPECT_EQ(it->second.triangles, sub.triangles) << key;
    if (fields & kWithColors) {
      EXPECT_EQ(it->second.colors, sub.colors) << key;
    }
    if (fields & kWithNormals) {
      EXPECT_EQ(it->second.normals, sub.normals) << key;
    }
  }
}

inline int runRosTests(int argc, char** argv, const char* node_name) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, node_name);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}

}  // namespace stereo_fusion::test
