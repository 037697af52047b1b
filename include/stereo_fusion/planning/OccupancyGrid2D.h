#pragma once
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "stereo_fusion/planning/PlanningMap.h"

namespace stereo_fusion {

/// A height band of the planning layer projected onto the ground plane (world x, y): the grid
/// that nav_msgs/OccupancyGrid, map_server and costmap_2d's static layer read. A column is
/// occupied if any cell of it in the band is, else free if any is free, else unknown.
struct OccupancyGrid2D {
  static constexpr int8_t kOccupied = 100, kFree = 0,
                          kUnknown = -1;  ///< nav_msgs/OccupancyGrid values
  double resolution_m = 0.0;
  double origin_x_m = 0.0, origin_y_m = 0.0;  ///< world position of cell (0, 0)'s outer corner
  int width = 0, height = 0;
  /// Row-major, row 0 at the smallest y (the OccupancyGrid convention).
  std::vector<int8_t> cells;
  /// The known columns spanned more than the window allowed: this is a window of them.
  bool windowed = false;
  int64_t known_width = 0, known_height = 0;  ///< the known columns' extent, in cells
  int8_t at(int x, int y) const { return cells[static_cast<size_t>(y) * width + x]; }
};

/// How large a projected grid may be (grid_max_cells): over it, a window of at most
/// floor(√max_cells) cells a side around `centre_m` (the camera), kept inside the known extent.
struct GridWindow {
  int64_t max_cells = 0;  ///< 0: no limit
  Eigen::Vector2d centre_m = Eigen::Vector2d::Zero();
};

/// The cells whose centre lies in [min_z_m, max_z_m], over the bounding box of the known ones,
/// or the window of it `window` allows.
OccupancyGrid2D projectOccupancy(const PlanningMap& planning, double min_z_m, double max_z_m,
                                 const GridWindow& window = {});

}  // namespace stereo_fusion
