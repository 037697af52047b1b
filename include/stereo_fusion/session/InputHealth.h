#pragma once
// How the node's input is doing now, for /diagnostics: rates and drops over a sliding time window
// (not averages since start, so one early drop does not colour the rest of the run) and whether
// the input stopped (a camera or driver that died). ROS-free: the node reads its counters into it
// once a report, with the time of a monotonic clock.
#include <cstdint>
#include <deque>
#include <limits>
#include <string>
#include <vector>

namespace stereo_fusion {

struct InputHealthConfig {
  /// Span of the rates and of the drop count (diagnostics_window_s); > 0.
  double window_s = 10.0;
  /// No frame for this long after the first one is stale input (input_timeout_s); 0 = never.
  double input_timeout_s = 2.0;
  /// What the stale message calls the measurements, one and several (input: depth: "depth
  /// image", "depth images"); not empty.
  std::string measurement = "disparity";
  std::string measurements = "disparities";
};
/// One message per invalid field (empty = valid).
std::vector<std::string> validateInputHealthConfig(const InputHealthConfig& config);

/// The node's counters since start, read at one instant. Each only grows; a smaller reading (an
/// estimate that fell back) is taken as the largest before it.
struct InputTotals {
  uint64_t disparities = 0;  ///< disparity messages received
  uint64_t frames = 0;       ///< frames received (disparity, image and camera_info matched)
  uint64_t dropped = 0;      ///< frames or disparities dropped, every reason
};

/// What the window says at the last sample.
struct InputWindowReport {
  /// The span the figures below cover: window_s once the samples reach back that far (up to one
  /// sample period more), less at start.
  double span_s = 0.0;
  double disparities_per_s = 0.0;
  double frames_per_s = 0.0;
  uint64_t dropped = 0;  ///< drops within the span
  bool first_frame_seen = false;
  /// Seconds since the sample that first saw the newest frame (so at most one sample period
  /// short of the truth); NaN before the first frame.
  double since_last_frame_s = std::numeric_limits<double>::quiet_NaN();
  bool stale = false;                 ///< since_last_frame_s ≥ input_timeout_s (with a timeout)
  bool disparities_arriving = false;  ///< stale, but disparities still came within the timeout
};

class InputHealth {
 public:
  explicit InputHealth(const InputHealthConfig& config) : config_(config) {}

  /// Reads `totals` at `now_s` (seconds of a monotonic clock, not decreasing between calls).
  void sample(double now_s, const InputTotals& totals);
  /// The window as of the last sample (all zero before the first).
  InputWindowReport report() const;
  /// The summary line of a stale input (empty when not stale).
  std::string staleMessage() const;

  const InputHealthConfig& config() const { return config_; }

 private:
  struct Sample {
    double t_s;
    InputTotals totals;
  };

  InputHealthConfig config_;
  /// The samples within the window, the oldest one at or before its start (the baseline).
  std::deque<Sample> samples_;
  double last_frame_change_s_ = -1.0;      // sample that first saw the current frame count
  double last_disparity_change_s_ = -1.0;  // likewise for disparities
};

}  // namespace stereo_fusion
