#pragma once
// The fleet costmap (issue 51, item 2): N robots' occupancy grids, each in its own map frame,
// merged into one grid in the operator frame. ROS-free: the base station reads each robot's
// grid and its alignment (tf's operator_frame → robotK/map) into it.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fusion/planning/OccupancyGrid2D.h"

namespace stereo_fusion {

struct FleetGridMergeConfig {
  /// Cell edge of the merged grid; finite, > 0. Cells lie on the operator frame's lattice
  /// (edges at integer multiples of it), so merges at different times line up.
  double resolution_m = 0.05;
  /// Largest merged grid, in cells (> 0): a bad alignment (a robot placed kilometres away)
  /// is refused instead of allocating gigabytes.
  int64_t max_cells = 4194304;
  /// Largest tilt of a robot's map frame against the operator's (the angle between the two z
  /// axes) a robot's grid is merged at; in [0, π/2). Over it the robot is refused.
  double max_tilt_rad = 0.05;
};
/// One message per invalid field (empty = valid).
std::vector<std::string> validateFleetGridMergeConfig(const FleetGridMergeConfig& config);

/// T_operator_robot on the ground plane. The grids are projections onto each map frame's own
/// x-y plane, so only the plane's motion is kept: x, y and the yaw of the best planar rotation
/// (atan2(R10 − R01, R00 + R11), exact for a pure yaw); z, roll and pitch are dropped, their
/// size kept as `tilt_rad` so a frame tilted beyond max_tilt_rad is refused, not flattened.
struct PlanarPose {
  double x_m = 0.0, y_m = 0.0, yaw_rad = 0.0;
  double tilt_rad = 0.0;  ///< angle between the robot's and the operator's z axes
};
PlanarPose planarPose(const Eigen::Isometry3d& T_operator_robot);

/// One robot's grid and where its map frame lies in the operator frame.
struct FleetGridInput {
  const OccupancyGrid2D* grid = nullptr;
  PlanarPose T_operator_robot;
};

/// A rectangle of merged-grid cells: columns [x0, x1), rows [y0, y1).
struct GridCellWindow {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x1 <= x0 || y1 <= y0; }
};

/// A robot left out of a merge: its index in the merge's input and why.
struct RobotRefusal {
  size_t robot = 0;
  std::string why;
  /// "robot <index>: <why>"
  std::string message() const { return "robot " + std::to_string(robot) + ": " + why; }
};

struct FleetGridMergeResult {
  /// The merged grid (resolution, origin, size, cells); empty when refused or no robot has cells.
  OccupancyGrid2D grid;
  /// Non-empty: the merge was refused (the grid would exceed max_cells); `grid` is empty and the
  /// caller keeps the grid it has.
  std::string error;
  /// One per robot left out (invalid grid or pose, tilted frame).
  std::vector<RobotRefusal> robots_refused;
  int robots_merged = 0;  ///< robots whose cells are in the grid
  int robots_empty = 0;   ///< robots with a grid of no cells (nothing to merge, not an error)
};

/// Merges robot grids by one rule, defined per merged cell:
///   - **sampling**: the merged cell takes, from each robot, the robot cell that contains the
///     merged cell's centre carried back into that robot's grid (centre c → R(yaw)ᵀ(c − t) →
///     floor((p − origin) / robot resolution)), if it lies inside the robot's grid — nearest-
///     cell resampling, one cell per robot. A centre exactly on a robot cell edge takes the
///     cell above it (floor). Where the merged resolution is coarser than a robot's cell / √2, a
///     rotated robot cell may contain no merged centre and is then not sampled at all: merge
///     at most at robot cell / √2 when obstacles one robot cell thin must survive every yaw.
///   - **combination**: occupied wins over free, free over unknown (robot values < 0 are
///     unknown, 0 free, > 0 occupied). A maximum over a rank, so the robots' order is irrelevant.
///   - **bounds**: the smallest lattice-aligned rectangle covering every merged robot's
///     transformed footprint (its four corners; corners within 10⁻⁶ cell of a lattice line
///     snap to it), so no merged cell whose centre lies in a robot's grid is left out.
class FleetGridMerge {
 public:
  /// `config` must be valid (validateFleetGridMergeConfig).
  explicit FleetGridMerge(const FleetGridMergeConfig& config);

  FleetGridMergeResult merge(const std::vector<FleetGridInput>& robots) const;

  /// The incremental form: re-merges only the cells of `window` in `merged` (a grid this
  /// merge made) from all robots, leaving the rest as it is. After robot K's grid or pose
  /// changed, the window is changedWindow(K before, K after, merged); the result equals a full
  /// merge's cells wherever the full merge has the same bounds. Robots refused by merge() are
  /// skipped here too.
  void remergeWindow(const std::vector<FleetGridInput>& robots, const GridCellWindow& window,
                     OccupancyGrid2D* merged) const;

  /// The cells of `merged` a robot's change can alter: the union of its footprints before and
  /// after, clipped to `merged`. nullopt when the footprint after reaches outside `merged`'s
  /// bounds (or is invalid): the bounds must grow, so a full merge() is needed.
  std::optional<GridCellWindow> changedWindow(const FleetGridInput& before,
                                              const FleetGridInput& after,
                                              const OccupancyGrid2D& merged) const;

  const FleetGridMergeConfig& config() const { return config_; }

 private:
  FleetGridMergeConfig config_;
};

}  // namespace stereo_fusion
