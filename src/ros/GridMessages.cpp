#include "stereo_fusion/ros/GridMessages.h"

#include <climits>
#include <cmath>

namespace stereo_fusion {

nav_msgs::OccupancyGrid toGridMessage(const OccupancyGrid2D& grid, const std::string& frame,
                                      const ros::Time& stamp) {
  nav_msgs::OccupancyGrid msg;
  msg.header.frame_id = frame;
  msg.header.stamp = stamp;
  msg.info.map_load_time = stamp;
  msg.info.resolution = static_cast<float>(grid.resolution_m);
  msg.info.width = static_cast<uint32_t>(grid.width);
  msg.info.height = static_cast<uint32_t>(grid.height);
  msg.info.origin.position.x = grid.origin_x_m;
  msg.info.origin.position.y = grid.origin_y_m;
  msg.info.origin.orientation.w = 1.0;
  msg.data = grid.cells;
  return msg;
}

bool fromGridMessage(const nav_msgs::OccupancyGrid& msg, OccupancyGrid2D* grid,
                     std::string* error) {
  const auto& info = msg.info;
  if (!(std::isfinite(info.resolution) && info.resolution > 0.0f)) {
    *error = "its resolution is not a finite number of metres > 0";
    return false;
  }
  if (!std::isfinite(info.origin.position.x) || !std::isfinite(info.origin.position.y)) {
    *error = "its origin is not finite";
    return false;
  }
  const auto& q = info.origin.orientation;
  if (q.x != 0.0 || q.y != 0.0 || q.z != 0.0 || !(std::abs(q.w) > 0.0)) {
    *error = "its origin is rotated (only axis-aligned grids are merged)";
    return false;
  }
  if (info.width > static_cast<uint32_t>(INT_MAX) || info.height > static_cast<uint32_t>(INT_MAX) ||
      msg.data.size() != static_cast<size_t>(info.width) * static_cast<size_t>(info.height)) {
    *error = "it holds " + std::to_string(msg.data.size()) + " cells, not width x height = " +
             std::to_string(static_cast<uint64_t>(info.width) * info.height);
    return false;
  }
  grid->resolution_m = info.resolution;
  grid->origin_x_m = info.origin.position.x;
  grid->origin_y_m = info.origin.position.y;
  grid->width = static_cast<int>(info.width);
  grid->height = static_cast<int>(info.height);
  grid->cells = msg.data;
  return true;
}

map_msgs::OccupancyGridUpdate toGridUpdateMessage(const GridPatch& patch, const std::string& frame,
                                                  const ros::Time& stamp) {
  map_msgs::OccupancyGridUpdate msg;
  msg.header.frame_id = frame;
  msg.header.stamp = stamp;
  msg.x = patch.x;
  msg.y = patch.y;
  msg.width = static_cast<uint32_t>(patch.width);
  msg.height = static_cast<uint32_t>(patch.height);
  msg.data = patch.cells;
  return msg;
}

bool fromGridUpdateMessage(const map_msgs::OccupancyGridUpdate& msg, GridPatch* patch,
                           std::string* error) {
  if (msg.width > static_cast<uint32_t>(INT_MAX) || msg.height > static_cast<uint32_t>(INT_MAX)) {
    *error = "its width or height does not fit an int";
    return false;
  }
  patch->x = msg.x;
  patch->y = msg.y;
  patch->width = static_cast<int>(msg.width);
  patch->height = static_cast<int>(msg.height);
  patch->cells = msg.data;
  return true;
}

}  // namespace stereo_fusion
