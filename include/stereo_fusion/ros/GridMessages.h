#pragma once
// nav_msgs/OccupancyGrid and map_msgs/OccupancyGridUpdate ↔ OccupancyGrid2D / GridPatch: the
// nodelet's ~occupancy_grid and the base station's fleet costmap speak the same messages.
#include <map_msgs/OccupancyGridUpdate.h>
#include <nav_msgs/OccupancyGrid.h>

#include <string>

#include "stereo_fusion/planning/GridPatch.h"
#include "stereo_fusion/planning/OccupancyGrid2D.h"

namespace stereo_fusion {

/// `grid` as a message in `frame` (origin orientation the identity).
nav_msgs::OccupancyGrid toGridMessage(const OccupancyGrid2D& grid, const std::string& frame,
                                      const ros::Time& stamp);

/// The message's grid; false with the reason (grid untouched) for a non-finite or non-positive
/// resolution, a non-finite origin, an origin rotated about any axis (the grids here are
/// axis-aligned in their frame), or data that is not width × height cells.
bool fromGridMessage(const nav_msgs::OccupancyGrid& msg, OccupancyGrid2D* grid, std::string* error);

/// `patch` as an update of a grid in `frame`.
map_msgs::OccupancyGridUpdate toGridUpdateMessage(const GridPatch& patch, const std::string& frame,
                                                  const ros::Time& stamp);

/// The update's rectangle and cells (not checked against any grid: applyGridPatch does that).
/// False with the reason when its size does not fit an int.
bool fromGridUpdateMessage(const map_msgs::OccupancyGridUpdate& msg, GridPatch* patch,
                           std::string* error);

}  // namespace stereo_fusion
