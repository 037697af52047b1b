#include "stereo_fusion/ros/FleetCostmap.h"

#include <tf2_eigen/tf2_eigen.h>

#include <filesystem>

#include "stereo_fusion/io/PlanningExport.h"
#include "stereo_fusion/planning/GridPatch.h"
#include "stereo_fusion/ros/GridMessages.h"

namespace stereo_fusion {

FleetCostmap::FleetCostmap(const FleetConfig& config, ros::NodeHandle inputs,
                           ros::NodeHandle outputs, const tf2_ros::Buffer* tf)
    : config_(config), merge_(config.grid), tf_(tf) {
  // Not latched: a subscriber gets the grid as it is when it connects, not the last full one
  // sent, which the updates after it have patched since (as the nodelet's ~occupancy_grid).
  grid_pub_ = outputs.advertise<nav_msgs::OccupancyGrid>(
      "occupancy_grid", 1, [this](const ros::SingleSubscriberPublisher& pub) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (merged_) pub.publish(merged_msg_);
      });
  updates_pub_ = outputs.advertise<map_msgs::OccupancyGridUpdate>("occupancy_grid_updates", 10);
  save_srv_ = outputs.advertiseService("save_grid", &FleetCostmap::saveGrid, this);
  for (const std::string& name : config_.robots) {
    robots_.push_back(std::make_unique<Robot>());
    Robot* robot = robots_.back().get();
    robot->name = name;
    ros::NodeHandle robot_nh(inputs, config_.robotNamespace(name));
    // Large queues: a full grid and its updates must be applied in order, none skipped.
    robot->grid_sub = robot_nh.subscribe<nav_msgs::OccupancyGrid>(
        "occupancy_grid", 10,
        [this, robot](const nav_msgs::OccupancyGrid::ConstPtr& msg) { onGrid(robot, msg); });
    robot->updates_sub = robot_nh.subscribe<map_msgs::OccupancyGridUpdate>(
        "occupancy_grid_updates", 100,
        [this, robot](const map_msgs::OccupancyGridUpdate::ConstPtr& msg) {
          onGridUpdate(robot, msg);
        });
  }
  timer_ = inputs.createWallTimer(ros::WallDuration(1.0 / config_.grid_publish_rate_hz),
                                  [this](const ros::WallTimerEvent&) { mergeAndPublish(); });
}

void FleetCostmap::onGrid(Robot* robot, const nav_msgs::OccupancyGrid::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  OccupancyGrid2D grid;
  std::string error;
  if (msg->header.frame_id.empty()) error = "it has no frame_id";
  if (!error.empty() || !fromGridMessage(*msg, &grid, &error)) {
    ++robot->refused;
    ROS_ERROR_THROTTLE(5.0, "fleet costmap: %s's occupancy grid refused: %s (its last grid kept)",
                       robot->name.c_str(), error.c_str());
    return;
  }
  robot->grid = std::move(grid);
  robot->frame_id = msg->header.frame_id;
  robot->grid_stamp = msg->header.stamp;
  ++robot->grids;
}

void FleetCostmap::onGridUpdate(Robot* robot, const map_msgs::OccupancyGridUpdate::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  GridPatch patch;
  std::string error;
  if (!robot->grid)
    error = "no full grid of it yet";
  else if (msg->header.stamp < robot->grid_stamp)  // the topics are not ordered with each other
    error = "older than its full grid (a late update of the grid before it)";
  else if (fromGridUpdateMessage(*msg, &patch, &error))
    applyGridPatch(patch, &*robot->grid, &error);
  if (!error.empty()) {
    // The robot sends the whole grid again when its extent moves; until then its copy here
    // lacks this window (counted, on /diagnostics).
    ++robot->refused;
    ROS_ERROR_THROTTLE(5.0, "fleet costmap: %s's occupancy grid update refused: %s",
                       robot->name.c_str(), error.c_str());
    return;
  }
  ++robot->updates;
}

void FleetCostmap::mergeAndPublish() {
  std::lock_guard<std::mutex> lock(mutex_);
  mergeLocked();
}

void FleetCostmap::mergeLocked() {
  std::vector<FleetGridInput> inputs;
  std::vector<Robot*> merged_robots;  // inputs[k] is merged_robots[k]'s
  for (auto& robot : robots_) {
    robot->problem.clear();
    if (!robot->grid) continue;
    try {
      const geometry_msgs::TransformStamped t =
          tf_->lookupTransform(config_.operator_frame, robot->frame_id, ros::Time(0));
      inputs.push_back({&*robot->grid, planarPose(tf2::transformToEigen(t))});
      merged_robots.push_back(robot.get());
    } catch (const tf2::TransformException& e) {
      robot->problem = std::string("no transform ") + config_.operator_frame + " -> " +
                       robot->frame_id + ": " + e.what();
      ROS_WARN_THROTTLE(10.0, "fleet costmap: %s left out: %s", robot->name.c_str(),
                        robot->problem.c_str());
    }
  }
  FleetGridMergeResult result = merge_.merge(inputs);
  for (const RobotRefusal& refusal : result.robots_refused) {
    const size_t k = refusal.robot;  // indexes `inputs`
    if (k < merged_robots.size()) merged_robots[k]->problem = refusal.why;
    ROS_WARN_THROTTLE(10.0, "fleet costmap: %s left out: %s",
                      k < merged_robots.size() ? merged_robots[k]->name.c_str() : "a robot",
                      refusal.why.c_str());
  }
  merge_error_ = result.error;
  if (!result.error.empty()) {
    ROS_ERROR_THROTTLE(10.0, "fleet costmap: merge refused, the last grid kept: %s",
                       result.error.c_str());
    return;
  }
  ++merges_;
  if (result.grid.width == 0 || result.grid.height == 0) return;  // nothing to show yet
  const ros::Time stamp = ros::Time::now();
  const std::optional<GridPatch> change =
      merged_ ? gridChange(*merged_, result.grid) : std::nullopt;
  if (change) {
    if (change->empty()) return;
    merged_ = std::move(result.grid);
    merged_msg_.data = merged_->cells;
    merged_msg_.header.stamp = stamp;
    updates_pub_.publish(toGridUpdateMessage(*change, config_.operator_frame, stamp));
    ++updates_sent_;
    return;
  }
  merged_ = std::move(result.grid);
  merged_msg_ = toGridMessage(*merged_, config_.operator_frame, stamp);
  grid_pub_.publish(merged_msg_);
  ++full_sent_;
}

bool FleetCostmap::saveGrid(SaveMesh::Request& req, SaveMesh::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::filesystem::path pgm(req.path);
  if (pgm.extension() != ".pgm") {
    res.success = false;
    res.message =
        "save_grid: '" + req.path + "' does not end in .pgm (the .yaml is written beside it)";
    ROS_ERROR("fleet costmap: %s", res.message.c_str());
    return true;
  }
  mergeLocked();  // the alignments and grids of now
  if (!merged_) {
    res.success = false;
    res.message = "save_grid: no robot's grid could be merged yet" +
                  (merge_error_.empty() ? std::string() : " (" + merge_error_ + ")");
    ROS_ERROR("fleet costmap: %s", res.message.c_str());
    return true;
  }
  const std::string yaml = std::filesystem::path(pgm).replace_extension(".yaml").string();
  std::string error;
  res.success = writeOccupancyMap(pgm.string(), yaml, *merged_, &error);
  res.message = res.success ? "wrote " + std::to_string(merged_->width) + " x " +
                                  std::to_string(merged_->height) + " cells to " + pgm.string() +
                                  " and " + yaml
                            : error;
  if (res.success)
    ROS_INFO("fleet costmap: save_grid: %s", res.message.c_str());
  else
    ROS_ERROR("fleet costmap: save_grid: %s", res.message.c_str());
  return true;
}

void FleetCostmap::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  size_t with_grid = 0, left_out = 0;
  for (const auto& robot : robots_) {
    with_grid += robot->grid ? 1 : 0;
    left_out += robot->problem.empty() ? 0 : 1;
  }
  if (!merge_error_.empty())
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "merge refused: " + merge_error_);
  else if (left_out > 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   std::to_string(left_out) + " robots left out of the merge");
  else if (with_grid < robots_.size())
    status.summary(diagnostic_msgs::DiagnosticStatus::OK,
                   "waiting for " + std::to_string(robots_.size() - with_grid) + " robots' grids");
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "merging");
  status.add("merges", merges_);
  status.add("full grids sent", full_sent_);
  status.add("updates sent", updates_sent_);
  status.add("width (cells)", merged_ ? merged_->width : 0);
  status.add("height (cells)", merged_ ? merged_->height : 0);
  for (const auto& robot : robots_) {
    status.add(robot->name + ": grids received", robot->grids);
    status.add(robot->name + ": updates applied", robot->updates);
    status.add(robot->name + ": grids and updates refused", robot->refused);
    status.add(robot->name + ": left out", robot->problem.empty() ? "no" : robot->problem);
  }
}

}  // namespace stereo_fusion
