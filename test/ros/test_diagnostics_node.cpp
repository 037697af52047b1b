// /diagnostics of the real nodelet as the input comes and goes (diagnostics.test: input_timeout_s
// 1, diagnostics_window_s 3): waiting before the first frame, ERROR "input stale" when frames
// stop and OK again when they come back; WARN while a dropped frame is within the window, OK
// once the window has passed it, its total since start kept.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <map>
#include <mutex>
#include <thread>

#include "../unit/TestSupport.h"
#include "RosTestSupport.h"

using namespace stereo_fusion;

namespace {

/// The fusion status's level, summary and values, as last reported (from one message, so a value
/// read right after waitFor() is of that report or a later one, never an earlier one).
class StatusWatcher {
 public:
  StatusWatcher() {
    sub_ = ros::NodeHandle().subscribe("/diagnostics", 10, &StatusWatcher::onMessage, this);
  }
  ~StatusWatcher() { sub_.shutdown(); }
  /// Waits until a report after this call has `level` and a summary containing `part`.
  bool waitFor(uint8_t level, const std::string& part, double timeout_s) {
    uint64_t after;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      after = reports_;
    }
    return test::waitFor(
        [&] {
          std::lock_guard<std::mutex> lock(mutex_);
          return reports_ > after && level_ == level && message_.find(part) != std::string::npos;
        },
        timeout_s);
  }
  std::string last() {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::to_string(level_) + " '" + message_ + "'";
  }
  /// The value of `key` as an integer (a double is cut), or -1 when it was not reported.
  long value(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = values_.find(key);
    return it == values_.end() ? -1 : std::stol(it->second);
  }

 private:
  void onMessage(const diagnostic_msgs::DiagnosticArray::ConstPtr& a) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : a->status)
      if (s.name.find(": fusion") != std::string::npos) {
        level_ = s.level;
        message_ = s.message;
        for (const auto& kv : s.values) values_[kv.key] = kv.value;
        ++reports_;
      }
  }
  ros::Subscriber sub_;
  std::mutex mutex_;
  uint8_t level_ = 255;
  std::string message_;
  std::map<std::string, std::string> values_;
  uint64_t reports_ = 0;
};

/// A camera that publishes the same view, freshly stamped, every 0.25 s while running.
class Camera {
 public:
  Camera() {
    ros::NodeHandle nh;
    disparity_pub_ = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 10);
    image_pub_ = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 10);
    info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 10);
    sim::AnalyticScene scene;
    scene.add(sim::makePlane({0, 0.3, 0}, {0, -1, 0}), {180, 160, 120});
    scene.add(sim::makeSphere({0.05, 0.1, 1.2}, 0.2), {200, 60, 60});
    const StereoCamera camera = *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1);
    frame_ = test::renderFrame(scene, camera, Eigen::Isometry3d::Identity());
  }
  ~Camera() { stop(); }
  bool connected() {
    return disparity_pub_.getNumSubscribers() > 0 && image_pub_.getNumSubscribers() > 0 &&
           info_pub_.getNumSubscribers() > 0;
  }
  void start() {
    running_ = true;
    thread_ = std::thread([this] {
      while (running_ && ros::ok()) {
        publish(false);
        ros::WallDuration(0.2).sleep();
      }
    });
  }
  void stop() {
    running_ = false;
    if (thread_.joinable()) thread_.join();
  }
  /// One frame; `bad_encoding`: its image in an encoding the node refuses (dropped: bad input).
  void publish(bool bad_encoding) {
    std::lock_guard<std::mutex> lock(publish_mutex_);
    test::FrameMessages m = test::frameMessages(frame_, &tf_);
    if (bad_encoding) m.image.encoding = "yuv422";
    ros::WallDuration(0.05).sleep();  // tf first
    disparity_pub_.publish(m.disparity);
    image_pub_.publish(m.image);
    info_pub_.publish(m.info);
  }

 private:
  ros::Publisher disparity_pub_, image_pub_, info_pub_;
  tf2_ros::TransformBroadcaster tf_;
  StereoFrame frame_;
  std::mutex publish_mutex_;  // the feeder thread and the test's own frames
  std::atomic<bool> running_{false};
  std::thread thread_;
};

constexpr uint8_t kOk = diagnostic_msgs::DiagnosticStatus::OK;
constexpr uint8_t kWarn = diagnostic_msgs::DiagnosticStatus::WARN;
constexpr uint8_t kError = diagnostic_msgs::DiagnosticStatus::ERROR;

}  // namespace

// One test: the two checks share the nodelet and the order matters (the first frame).
TEST(DiagnosticsNode, StaleInputIsAnErrorUntilFramesComeAndDropsWarnOnlyWithinTheWindow) {
  StatusWatcher status;
  test::DiagnosticsWatcher diagnostics;
  Camera camera;
  ASSERT_TRUE(test::waitFor([&] { return camera.connected(); }, 30.0)) << "no nodelet";
  ASSERT_TRUE(test::waitForTfSubscriber(30.0)) << "the nodelet's tf listener did not connect";

  // Before the first frame: waiting, not stale, however long (two reports: > input_timeout_s).
  ASSERT_TRUE(diagnostics.waitForNextReport(30.0));
  ASSERT_TRUE(diagnostics.waitForNextReport(30.0));
  EXPECT_TRUE(status.waitFor(kOk, "waiting for the first frame", 5.0)) << status.last();

  camera.start();
  ASSERT_TRUE(test::waitFor([&] { return diagnostics.value("frames fused") >= 3; }, 60.0));
  EXPECT_TRUE(status.waitFor(kOk, "fusing", 10.0)) << status.last();
  EXPECT_GE(status.value("since the last frame (s)"), 0) << "a number once a frame came";

  // The camera dies: ERROR within the timeout (1 s) and a report period (1 s), and some margin.
  camera.stop();
  ASSERT_TRUE(status.waitFor(kError, "input stale: no frame for", 10.0)) << status.last();
  EXPECT_TRUE(status.waitFor(kError, "no disparity either", 3.0)) << status.last();
  EXPECT_GE(status.value("since the last frame (s)"), 1);
  const long fused = diagnostics.value("frames fused");

  // It comes back: OK again.
  camera.start();
  ASSERT_TRUE(status.waitFor(kOk, "fusing", 10.0)) << status.last();
  EXPECT_TRUE(test::waitFor([&] { return diagnostics.value("frames fused") > fused; }, 30.0));

  // One bad frame among good ones: WARN while it is within the 3 s window, then OK again with
  // the drop still counted since start.
  const long dropped_before = status.value("frames dropped since start");
  ASSERT_GE(dropped_before, 0);
  camera.publish(true);
  ASSERT_TRUE(status.waitFor(kWarn, "dropped in the last", 10.0)) << status.last();
  EXPECT_GE(status.value("frames dropped in the window"), 1);
  ASSERT_TRUE(status.waitFor(kOk, "fusing", 10.0)) << status.last();
  EXPECT_EQ(status.value("frames dropped in the window"), 0);
  EXPECT_EQ(status.value("frames dropped since start"), dropped_before + 1);
  EXPECT_EQ(status.value("dropped: bad input"), 1);
  camera.stop();
}

int main(int argc, char** argv) {
  return test::runRosTests(argc, argv, "stereo_fusion_diagnostics_test");
}
