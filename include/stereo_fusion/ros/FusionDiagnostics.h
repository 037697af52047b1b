#pragma once
// /diagnostics of the node: every counter of the session (frames by reason, trajectories by
// outcome, clears), of the frame input, and the timings, once a second; the input's rates and
// drops over diagnostics_window_s and stale input (input_timeout_s) by InputHealth.
#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include <memory>
#include <string>

#include "stereo_fusion/ros/FrameInput.h"
#include "stereo_fusion/ros/NodeStats.h"
#include "stereo_fusion/ros/RosParameters.h"
#include "stereo_fusion/ros/TrajectoryInput.h"
#include "stereo_fusion/session/InputHealth.h"
#include "stereo_fusion/session/MappingSession.h"

namespace stereo_fusion {

/// What the input's measurements are called in the diagnostics' keys and messages.
struct MeasurementNames {
  std::string one;      ///< "disparity", "depth image"
  std::string several;  ///< "disparities", "depth images"
  static MeasurementNames of(InputMode input);
};

class FusionDiagnostics {
 public:
  FusionDiagnostics(ros::NodeHandle& nh, ros::NodeHandle& pnh, const NodeConfig& node,
                    MappingSession* session, const FrameInput* frames,
                    const TrajectoryInput* trajectories, const NodeStats* stats);

 private:
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  /// Disparities neither matched into a frame nor refused (some wait for their image).
  uint64_t unmatchedDisparities() const;
  /// The input's counters now, as InputHealth reads them.
  InputTotals inputTotals(uint64_t unmatched) const;
  /// Seconds on a monotonic clock (a stale input is judged by it, not by wall or ROS time).
  static double monotonicNowS();

  /// An operation holding the map longer than this is reported as an ERROR, naming its stage.
  static constexpr double kStalledAfterS = 1.0;

  const NodeConfig& node_;
  MappingSession* session_;
  const FrameInput* frames_;
  const TrajectoryInput* trajectories_;
  const NodeStats* stats_;
  const MeasurementNames names_;  // before input_health_, which is built with them
  ros::WallTime started_;
  InputHealth input_health_;              // sampled by diagnose() only (the timer's thread)
  MappingSession::MapStatus map_status_;  // the last read (only the diagnostics thread uses it)
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer timer_;
};

}  // namespace stereo_fusion
