#include "stereo_fusion/ros/PlanningPublisher.h"

#include "stereo_fusion/ros/GridMessages.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl_conversions/pcl_conversions.h>
#include <sensor_msgs/PointCloud2.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace stereo_fusion {

namespace {

bool sameExtent(const OccupancyGrid2D& a, const OccupancyGrid2D& b) {
  return a.width == b.width && a.height == b.height && a.origin_x_m == b.origin_x_m &&
         a.origin_y_m == b.origin_y_m && a.resolution_m == b.resolution_m;
}

int32_t floorToMultiple(int32_t v, int32_t m) { return floorDiv(v, m) * m; }

}  // namespace

OccupancyGrid2D alignGrid(const OccupancyGrid2D& grid, int align) {
  if (grid.width == 0 || grid.height == 0 || align <= 1) return grid;
  // Cell indices of the grid's corner: the origin is a whole number of cells (projectOccupancy).
  const auto x0 = static_cast<int32_t>(std::lround(grid.origin_x_m / grid.resolution_m));
  const auto y0 = static_cast<int32_t>(std::lround(grid.origin_y_m / grid.resolution_m));
  const int32_t ax0 = floorToMultiple(x0, align), ay0 = floorToMultiple(y0, align);
  const int32_t ax1 = floorToMultiple(x0 + grid.width - 1, align) + align;  // exclusive
  const int32_t ay1 = floorToMultiple(y0 + grid.height - 1, align) + align;
  OccupancyGrid2D aligned;
  aligned.resolution_m = grid.resolution_m;
  aligned.width = ax1 - ax0;
  aligned.height = ay1 - ay0;
  aligned.origin_x_m = ax0 * grid.resolution_m;
  aligned.origin_y_m = ay0 * grid.resolution_m;
  aligned.cells.assign(static_cast<size_t>(aligned.width) * aligned.height,
                       OccupancyGrid2D::kUnknown);
  for (int y = 0; y < grid.height; ++y)
    std::copy_n(
        grid.cells.begin() + static_cast<size_t>(y) * grid.width, grid.width,
        aligned.cells.begin() + static_cast<size_t>(y + y0 - ay0) * aligned.width + (x0 - ax0));
  return aligned;
}

PlanningPublisher::PlanningPublisher(ros::NodeHandle& pnh, const NodeConfig& node,
                                     const MapperConfig& mapper, const OutputCadence& cadence,
                                     MappingSession* session, NodeStats* stats)
    : node_(node),
      grid_min_z_m_(mapper.grid_min_z_m),
      grid_max_z_m_(mapper.grid_max_z_m),
      session_(session),
      stats_(stats) {
  // Not latched: a subscriber gets the grid as it is when it connects (onGridSubscriber), not
  // the last full one sent, which the updates after it have patched since.
  grid_pub_ = pnh.advertise<nav_msgs::OccupancyGrid>(
      "occupancy_grid", 1,
      [this](const ros::SingleSubscriberPublisher& pub) { onGridSubscriber(pub); });
  grid_updates_pub_ = pnh.advertise<map_msgs::OccupancyGridUpdate>("occupancy_grid_updates", 10);
  slice_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("esdf_slice", 1);
  occupied_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("occupied_voxels", 1);
  if (!mapper.planning_enabled) {
    ROS_INFO(
        "stereo_fusion: planning_enabled is false: ~occupancy_grid, ~esdf_slice and "
        "~occupied_voxels stay silent");
    return;
  }
  timer_ = pnh.createWallTimer(ros::WallDuration(cadence.planningPeriodS()),
                               [this](const ros::WallTimerEvent&) { tick(); });
}

void PlanningPublisher::onMapReplaced(const MapReplaced&) { replaced_ = true; }

void PlanningPublisher::onGridSubscriber(const ros::SingleSubscriberPublisher& pub) {
  std::lock_guard<std::mutex> lock(grid_mutex_);
  if (grid_) pub.publish(grid_msg_);
}

void PlanningPublisher::tick() {
  std::unique_lock<std::mutex> tick_lock(tick_mutex_, std::try_to_lock);
  if (!tick_lock.owns_lock()) return;  // the previous tick still runs
  const bool want_grid =
      grid_pub_.getNumSubscribers() > 0 || grid_updates_pub_.getNumSubscribers() > 0;
  const bool want_slice = slice_pub_.getNumSubscribers() > 0;
  const bool want_occupied = occupied_pub_.getNumSubscribers() > 0;
  if (!want_grid) {
    // Nobody holds a grid: the next subscriber gets a full one at the first tick after it came.
    std::lock_guard<std::mutex> lock(grid_mutex_);
    grid_.reset();
  }

  // The map lock is held only while the update reads the TSDF; the distance field's update
  // and the copies of what the topics need run while frames are fused.
  bool have_layer = false, full = false;
  // Before the update: every edit that returned before it is in what this tick sends.
  const ros::Time stamp = ros::Time::now();
  OccupancyGrid2D grid;
  std::vector<std::array<float, 4>> slice;  // x y z distance
  std::vector<std::array<float, 3>> occupied;
  GridWindow window;
  if (want_grid) session_->read([&](const Mapper& m) { window = m.occupancyGridWindow(); });
  session_->updatePlanning([&](const PlanningMap& planning, const PlanningPass& pass) {
    have_layer = true;
    const PlanningUpdateStats& s = pass.stats;
    if (s.tsdf_blocks > 0 || s.blocks_allocated > 0 || s.blocks_erased > 0)
      stats_->recordPlanningUpdate(pass.esdf_ms);
    if (want_grid) {
      grid = projectOccupancy(planning, grid_min_z_m_, grid_max_z_m_, window);
      full = replaced_.exchange(false);
    }
    if (want_slice || want_occupied) {
      const PlanningGrid& g = planning.grid();
      const auto slice_z = static_cast<int32_t>(std::floor(node_.esdf_slice_height_m / g.cell_m));
      planning.forEachKnownCell([&](const CellIndex& c, CellState state, double distance_m) {
        if (want_slice && c.z == slice_z) {
          const Eigen::Vector3d p = g.centre(c);
          slice.push_back({float(p.x()), float(p.y()), float(p.z()), float(distance_m)});
        }
        if (want_occupied && state == CellState::kOccupied) {
          const Eigen::Vector3d p = g.centre(c);
          occupied.push_back({float(p.x()), float(p.y()), float(p.z())});
        }
      });
    }
  });
  if (!have_layer) return;

  // After it: the messages.
  if (want_grid) {
    const OccupancyGrid2D aligned = alignGrid(grid, kGridAlignCells);
    stats_->grid_width = static_cast<uint32_t>(aligned.width);
    stats_->grid_height = static_cast<uint32_t>(aligned.height);
    stats_->grid_windowed = grid.windowed;
    if (grid.windowed)
      ROS_WARN_THROTTLE(10.0,
                        "stereo_fusion: the occupancy grid is a %d x %d window around the camera: "
                        "the known columns span %lld x %lld cells, more than grid_max_cells",
                        grid.width, grid.height, static_cast<long long>(grid.known_width),
                        static_cast<long long>(grid.known_height));
    publishGrid(aligned, full, stamp);
  }
  std_msgs::Header header;
  header.frame_id = node_.world_frame;
  header.stamp = stamp;
  if (want_slice) {
    // voxblox's convention: x y z and the distance in the field "intensity" (rviz colours by it).
    pcl::PointCloud<pcl::PointXYZI> cloud;
    cloud.reserve(slice.size());
    for (const auto& p : slice) {
      pcl::PointXYZI point;
      point.x = p[0], point.y = p[1], point.z = p[2];
      point.intensity = p[3];
      cloud.push_back(point);
    }
    sensor_msgs::PointCloud2 msg;
    pcl::toROSMsg(cloud, msg);
    msg.header = header;
    slice_pub_.publish(msg);
  }
  if (want_occupied) {
    pcl::PointCloud<pcl::PointXYZ> cloud;
    cloud.reserve(occupied.size());
    for (const auto& p : occupied) cloud.push_back(pcl::PointXYZ(p[0], p[1], p[2]));
    sensor_msgs::PointCloud2 msg;
    pcl::toROSMsg(cloud, msg);
    msg.header = header;
    occupied_pub_.publish(msg);
  }
}

void PlanningPublisher::publishGrid(const OccupancyGrid2D& grid, bool full,
                                    const ros::Time& stamp) {
  std::lock_guard<std::mutex> lock(grid_mutex_);
  if (!full && grid_ && sameExtent(*grid_, grid)) {
    // The bounding window of the cells that changed.
    int x0 = grid.width, y0 = grid.height, x1 = -1, y1 = -1;
    for (int y = 0; y < grid.height; ++y)
      for (int x = 0; x < grid.width; ++x)
        if (grid.at(x, y) != grid_->at(x, y)) {
          x0 = std::min(x0, x), x1 = std::max(x1, x);
          y0 = std::min(y0, y), y1 = std::max(y1, y);
        }
    if (x1 < 0) return;  // nothing changed
    map_msgs::OccupancyGridUpdate update;
    update.header.frame_id = node_.world_frame;
    update.header.stamp = stamp;
    update.x = x0;
    update.y = y0;
    update.width = static_cast<uint32_t>(x1 - x0 + 1);
    update.height = static_cast<uint32_t>(y1 - y0 + 1);
    update.data.reserve(static_cast<size_t>(update.width) * update.height);
    for (int y = y0; y <= y1; ++y)
      update.data.insert(update.data.end(),
                         grid.cells.begin() + static_cast<size_t>(y) * grid.width + x0,
                         grid.cells.begin() + static_cast<size_t>(y) * grid.width + x1 + 1);
    grid_ = grid;
    grid_msg_.data = grid.cells;
    grid_msg_.header.stamp = stamp;
    grid_updates_pub_.publish(update);
    return;
  }
  grid_ = grid;
  grid_msg_ = toGridMessage(grid, node_.world_frame, stamp);
  grid_pub_.publish(grid_msg_);
}

}  // namespace stereo_fusion
