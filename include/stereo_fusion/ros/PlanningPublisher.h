#pragma once
// The node's outputs of the planning layer, at planning_publish_rate_hz: ~occupancy_grid
// (nav_msgs/OccupancyGrid of the height band) with ~occupancy_grid_updates (map_msgs/
// OccupancyGridUpdate of the changed window), ~esdf_slice and ~occupied_voxels
// (sensor_msgs/PointCloud2). The layer itself is brought up to date at that rate too, whether
// anyone listens or not. No PCL header here: only PlanningPublisher.cpp includes them.
#include <map_msgs/OccupancyGridUpdate.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>

#include <atomic>
#include <mutex>
#include <optional>

#include "stereo_fusion/planning/OccupancyGrid2D.h"
#include "stereo_fusion/ros/NodeStats.h"
#include "stereo_fusion/ros/RosParameters.h"
#include "stereo_fusion/session/MappingSession.h"
#include "stereo_fusion/session/OutputCadence.h"

namespace stereo_fusion {

/// Each tick takes the session's map lock only while the update reads the changed TSDF blocks
/// (MappingSession::updatePlanning()); the distance field's update and the copies the
/// subscribed topics need (the projected grid, the slice's and the occupied cells) run beside
/// the frames, and the messages are built and published after them.
///
/// The grid: a subscriber gets the current full grid when it connects (as costmap_2d's own
/// publisher does), then an update of the bounding window of the cells that changed; a full
/// grid goes to everyone when the grid's extent moves or after a wholesale change of the map
/// (reset, load, a loop-closure correction: onMapReplaced()). So the first grid a subscriber
/// receives, patched with every update after it, is the current grid.
class PlanningPublisher {
 public:
  /// `private_nh`: the namespace of the topics; its callback queue runs the timer.
  /// The layer's update and its topics run every cadence.planningPeriodS().
  PlanningPublisher(ros::NodeHandle& private_nh, const NodeConfig& node, const MapperConfig& mapper,
                    const OutputCadence& cadence, MappingSession* session, NodeStats* stats);
  ~PlanningPublisher() { stop(); }
  /// Stops the timer, waiting for a tick in progress (before the session goes).
  void stop() { timer_.stop(); }
  /// The session's listener (map lock held): the next tick sends the grid whole.
  void onMapReplaced(const MapReplaced& replaced);

  /// Grid columns are aligned to multiples of this many cells, so that a grid growing by a
  /// few cells at its edge does not resend the whole grid every tick.
  static constexpr int kGridAlignCells = 16;

 private:
  void tick();
  /// Sends `grid`: whole (to every subscriber) when `full` or its extent moved, else as the
  /// window of the cells that differ from the previous one (nothing if none does).
  void publishGrid(const OccupancyGrid2D& grid, bool full, const ros::Time& stamp);
  void onGridSubscriber(const ros::SingleSubscriberPublisher& pub);

  const NodeConfig& node_;
  const double grid_min_z_m_, grid_max_z_m_;
  MappingSession* session_;
  NodeStats* stats_;
  ros::Publisher grid_pub_, grid_updates_pub_, slice_pub_, occupied_pub_;
  ros::WallTimer timer_;
  std::mutex tick_mutex_;  // one tick at a time (the timer may run on a multi-threaded queue)
  std::atomic<bool> replaced_{true};  // send the next grid whole
  std::mutex grid_mutex_;  // guards the two below (the tick and new subscribers' callbacks)
  std::optional<OccupancyGrid2D> grid_;  // the grid subscribers hold now
  nav_msgs::OccupancyGrid grid_msg_;     // the same as a message, for a new subscriber
};

/// `grid` widened with unknown cells to the multiples of `align` cells around it (an empty grid
/// stays empty).
OccupancyGrid2D alignGrid(const OccupancyGrid2D& grid, int align);

}  // namespace stereo_fusion
