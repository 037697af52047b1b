#include "stereo_fusion/ros/FleetConfig.h"

#include <cctype>
#include <cmath>
#include <set>

namespace stereo_fusion {

namespace {

/// A ROS graph name token: a letter, then letters, digits or '_'.
bool isNameToken(const std::string& name) {
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

/// A tf frame id: not empty, no leading '/' (tf2 refuses one), no white space.
bool isFrameId(const std::string& frame) {
  if (frame.empty() || frame[0] == '/') return false;
  for (char c : frame)
    if (std::isspace(static_cast<unsigned char>(c))) return false;
  return true;
}

}  // namespace

std::vector<std::string> validateFleetConfig(const FleetConfig& config) {
  std::vector<std::string> errors;
  std::set<std::string> seen;
  for (const std::string& robot : config.robots) {
    if (!isNameToken(robot))
      errors.push_back("robots: '" + robot +
                       "' is not a ROS name token (a letter, then letters, digits or '_')");
    else if (!seen.insert(robot).second)
      errors.push_back("robots: '" + robot + "' is listed twice");
  }
  if (!isNameToken(config.robot_node))
    errors.push_back("robot_node: '" + config.robot_node +
                     "' is not a ROS name token (a letter, then letters, digits or '_')");
  if (!isFrameId(config.operator_frame))
    errors.push_back("operator_frame: '" + config.operator_frame +
                     "' is not a tf frame id (not empty, no leading '/', no spaces)");
  if (!(std::isfinite(config.grid_publish_rate_hz) && config.grid_publish_rate_hz >= 0.0 &&
        config.grid_publish_rate_hz <= 100.0))
    errors.push_back("grid_publish_rate_hz must be in [0, 100] (0: no fleet costmap)");
  // Its messages name the merge's fields: grid_resolution_m, grid_max_cells, grid_max_tilt_rad.
  for (const std::string& e : validateFleetGridMergeConfig(config.grid))
    errors.push_back(e + " (the base station's grid_* parameters)");
  return errors;
}

}  // namespace stereo_fusion
