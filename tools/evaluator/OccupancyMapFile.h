#pragma once
// A 2D occupancy map in ROS map_server's format (a YAML description and an image), read the way
// map_server reads it, so a score counts what a navigation stack would see.

#include <cstdint>
#include <string>
#include <vector>

namespace stereo_fusion::eval {

/// The map as map_server publishes it (nav_msgs/OccupancyGrid values). Its own type rather than
/// the planning layer's OccupancyGrid2D: this side reads files, whatever wrote them.
struct OccupancyMap {
  static constexpr int8_t kOccupied = 100, kFree = 0, kUnknown = -1;
  double resolution_m = 0.0;
  double origin_x_m = 0.0, origin_y_m = 0.0;  ///< world position of cell (0, 0)'s outer corner
  int width = 0, height = 0;
  /// Row-major, row 0 at the smallest y (the image's bottom row). Trinary maps hold 100, 0 or -1;
  /// "scale" maps also 1..99 between the thresholds (known, not occupied).
  std::vector<int8_t> cells;
  int8_t at(int x, int y) const { return cells[static_cast<size_t>(y) * width + x]; }
};

/// Reads `yaml_path` (image relative to the YAML's folder, resolution, origin, negate,
/// occupied_thresh, free_thresh, mode trinary or scale) and its 8-bit image. A pixel of value v
/// (channels averaged) has occupancy p = (255 − v) / 255 (v / 255 with negate): occupied above
/// occupied_thresh, free below free_thresh, unknown between (trinary). Refuses a rotated origin
/// (yaw ≠ 0) and mode raw. False with a message naming the file on any problem.
bool readOccupancyMap(const std::string& yaml_path, OccupancyMap* map, std::string* error);

}  // namespace stereo_fusion::eval
