#pragma once
// A rectangle of new cell values for an occupancy grid: what map_msgs/OccupancyGridUpdate
// carries. The fleet costmap applies the robots' updates to its copies of their grids with it,
// and sends its own merged grid's changes as one.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "stereo_fusion/planning/OccupancyGrid2D.h"

namespace stereo_fusion {

/// Cells of columns [x, x + width) and rows [y, y + height), row-major, row 0 at y.
struct GridPatch {
  int x = 0, y = 0, width = 0, height = 0;
  std::vector<int8_t> cells;
  bool empty() const { return width <= 0 || height <= 0; }
};

/// Writes `patch` into `grid`. False with the reason, `grid` unchanged, when the patch's
/// rectangle is negative or not inside the grid, or it does not hold width × height cells.
bool applyGridPatch(const GridPatch& patch, OccupancyGrid2D* grid, std::string* error);

/// The smallest patch that turns `before` into `after` (an empty patch when they are equal);
/// nullopt when they differ in resolution, origin or size, so only the whole grid will do.
std::optional<GridPatch> gridChange(const OccupancyGrid2D& before, const OccupancyGrid2D& after);

}  // namespace stereo_fusion
