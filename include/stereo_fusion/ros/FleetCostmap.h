#pragma once
// The base station's fleet costmap (issue 51, item 2): each robot's ~occupancy_grid (patched by
// its ~occupancy_grid_updates) placed in the operator frame by tf and merged by FleetGridMerge
// into one grid, published as ~occupancy_grid (+ ~occupancy_grid_updates) and saved in
// map_server format.
#include <diagnostic_updater/diagnostic_updater.h>
#include <map_msgs/OccupancyGridUpdate.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <stereo_fusion/SaveMesh.h>
#include <tf2_ros/buffer.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "stereo_fusion/planning/FleetGridMerge.h"
#include "stereo_fusion/planning/OccupancyGrid2D.h"
#include "stereo_fusion/ros/FleetConfig.h"

namespace stereo_fusion {

/// In: `/<robot>/<robot_node>/occupancy_grid` and `.../occupancy_grid_updates` of each robot;
/// tf operator_frame → each grid's frame_id (the latest transform, so a new alignment is used at
/// the next merge). Out (on `outputs`): `occupancy_grid` (the whole merged grid: to a new
/// subscriber, and when its extent changes), `occupancy_grid_updates` (the window of the cells
/// that changed since, otherwise), service `save_grid` (SaveMesh: `path` = the .pgm; the .yaml
/// beside it). Merges every 1 / grid_publish_rate_hz s of wall time.
class FleetCostmap {
 public:
  /// `config` must be valid (validateFleetConfig) with robots and grid_publish_rate_hz > 0; `tf`
  /// must outlive this object.
  FleetCostmap(const FleetConfig& config, ros::NodeHandle inputs, ros::NodeHandle outputs,
               const tf2_ros::Buffer* tf);

  /// Merges the grids held now and publishes what changed.
  void mergeAndPublish();
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

 private:
  struct Robot {
    std::string name;
    std::optional<OccupancyGrid2D> grid;  ///< as the robot's messages built it
    std::string frame_id;
    ros::Time grid_stamp;  ///< the full grid's: an update stamped before it is late, refused
    std::string problem;   ///< why it was left out of the last merge (empty: merged or no grid)
    uint64_t grids = 0, updates = 0, refused = 0;
    ros::Subscriber grid_sub, updates_sub;
  };
  void onGrid(Robot* robot, const nav_msgs::OccupancyGrid::ConstPtr& msg);
  void onGridUpdate(Robot* robot, const map_msgs::OccupancyGridUpdate::ConstPtr& msg);
  /// Called with mutex_ held.
  void mergeLocked();
  bool saveGrid(SaveMesh::Request& req, SaveMesh::Response& res);

  FleetConfig config_;
  FleetGridMerge merge_;
  const tf2_ros::Buffer* tf_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Robot>> robots_;
  std::optional<OccupancyGrid2D> merged_;  ///< the grid subscribers hold now
  nav_msgs::OccupancyGrid merged_msg_;     ///< the same as a message, for a new subscriber
  std::string merge_error_;                ///< the last merge's refusal (empty: none)
  uint64_t merges_ = 0, full_sent_ = 0, updates_sent_ = 0;
  ros::Publisher grid_pub_, updates_pub_;
  ros::ServiceServer save_srv_;
  ros::WallTimer timer_;
};

}  // namespace stereo_fusion
