#pragma once
// The base station's fleet parameters (issue 51): which robots it follows and the operator frame
// it places them in. ROS-free (validated in unit tests); the MeshAssembler reads it from its
// private parameters.
#include <string>
#include <vector>

#include "stereo_fusion/planning/FleetGridMerge.h"

namespace stereo_fusion {

struct FleetConfig {
  /// Robot names; empty: the single-robot assembler (topics `mesh_update` / `get_full_mesh`
  /// remapped by the launch file). Each name is one ROS name token (a letter, then letters,
  /// digits, '_') and the robot's top-level namespace: its fusion nodelet is
  /// `/<name>/<robot_node>`. Unique.
  std::vector<std::string> robots;
  /// The fusion nodelet's name inside each robot's namespace.
  std::string robot_node = "stereo_fusion";
  /// The frame of the operator map: each robot's blocks and grid are placed by tf's transform
  /// operator_frame → the robot's world frame (the frame_id of its messages).
  std::string operator_frame = "map";
  /// The fleet costmap: its merge (resolution, size limit, tilt) and how often it is re-merged
  /// and published (Hz, (0, 100]; 0 turns the fleet costmap off).
  FleetGridMergeConfig grid;
  double grid_publish_rate_hz = 1.0;

  bool fleet() const { return !robots.empty(); }
  /// The robot's fusion nodelet's namespace: `/<robot>/<robot_node>`.
  std::string robotNamespace(const std::string& robot) const {
    return "/" + robot + "/" + robot_node;
  }
};

/// One message per invalid field (empty = valid), naming the parameter.
std::vector<std::string> validateFleetConfig(const FleetConfig& config);

}  // namespace stereo_fusion
