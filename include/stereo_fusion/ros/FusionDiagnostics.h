#pragma once
// /diagnostics of the node: every counter of the session (frames by reason, trajectories by
// outcome, clears), of the frame input, and the timings, once a second.
#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include <memory>

#include "stereo_fusion/ros/FrameInput.h"
#include "stereo_fusion/ros/NodeStats.h"
#include "stereo_fusion/ros/RosParameters.h"
#include "stereo_fusion/ros/TrajectoryInput.h"
#include "stereo_fusion/session/MappingSession.h"

namespace stereo_fusion {

class FusionDiagnostics {
 public:
  FusionDiagnostics(ros::NodeHandle& nh, ros::NodeHandle& pnh, const NodeConfig& node,
                    MappingSession* session, const FrameInput* frames,
                    const TrajectoryInput* trajectories, const NodeStats* stats);

 private:
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  /// An operation holding the map longer than this is reported as an ERROR, naming its stage.
  static constexpr double kStalledAfterS = 1.0;

  const NodeConfig& node_;
  MappingSession* session_;
  const FrameInput* frames_;
  const TrajectoryInput* trajectories_;
  const NodeStats* stats_;
  ros::WallTime started_;
  MappingSession::MapStatus map_status_;  // the last read (only the diagnostics thread uses it)
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer timer_;
};

}  // namespace stereo_fusion
