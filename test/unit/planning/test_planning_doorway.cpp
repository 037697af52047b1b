// A doorway 0.80 m wide between two rooms stays passable in the 2D occupancy grid a planner
// reads (projectOccupancy, the grid occupancy.pgm is written from): noisy stereo views from both
// rooms, fused, leave the jambs where they are and the doorway's floor free, so an A* over the
// grid with a 0.25 m robot radius (costmap_2d's inflation: no occupied cell centre within the
// radius) goes from one room's middle to the other's through the door, on a near-direct route.
// Not vacuous: the wall on both sides of the door is occupied, and a 0.45 m robot (0.9 m wide,
// wider than the door) finds no way through.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <queue>
#include <sstream>
#include <string>
#include <vector>

#include "QuickMode.h"
#include "TestSupport.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/planning/OccupancyGrid2D.h"

namespace stereo_fusion {
namespace {

using test::renderFrame;
using test::vgaCamera;

// Two rooms 4 m deep side by side (x < 0: room A, x > 0: room B), 4 m wide and 2.5 m high,
// separated by a 10 cm wall in the plane x = 0 with one doorway 0.80 m wide and 2 m high. The
// door's centre is off the planning grid's cell boundaries (8 cm cells from 0) so that the
// jambs fall inside cells, as they would in a real map.
constexpr double kWallHalfThickness_m = 0.05;
constexpr double kDoorCentreY_m = 0.03;
constexpr double kDoorHalfWidth_m = 0.40;
constexpr double kDoorHeight_m = 2.0;
constexpr double kRoomHalfDepth_m = 4.0, kRoomHalfWidth_m = 2.0, kRoomHeight_m = 2.5;

sim::AnalyticScene twoRoomsScene() {
  sim::AnalyticScene scene;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.0, 0.0, kRoomHeight_m / 2);
  scene.add(
      sim::makeRoom(T, Eigen::Vector3d(kRoomHalfDepth_m, kRoomHalfWidth_m, kRoomHeight_m / 2)));
  // The wall's pieces reach into the room's side walls and ceiling (solids may overlap), so no
  // seam opens where they meet.
  const double outer_m = kRoomHalfWidth_m + 0.1, top_m = kRoomHeight_m + 0.1;
  const double jamb_low_m = kDoorCentreY_m - kDoorHalfWidth_m,
               jamb_high_m = kDoorCentreY_m + kDoorHalfWidth_m;
  const auto addWallBox = [&](double y0_m, double y1_m, double z0_m, double z1_m) {
    Eigen::Isometry3d T_box = Eigen::Isometry3d::Identity();
    T_box.translation() = Eigen::Vector3d(0.0, (y0_m + y1_m) / 2, (z0_m + z1_m) / 2);
    scene.add(sim::makeBox(T_box, Eigen::Vector3d(kWallHalfThickness_m, (y1_m - y0_m) / 2,
                                                  (z1_m - z0_m) / 2)),
              {180, 160, 140});
  };
  addWallBox(-outer_m, jamb_low_m, 0.0, top_m);               // beside the door, −y
  addWallBox(jamb_high_m, outer_m, 0.0, top_m);               // beside the door, +y
  addWallBox(jamb_low_m, jamb_high_m, kDoorHeight_m, top_m);  // the lintel
  return scene;
}

/// Camera poses in room A (x < 0); room B's are their mirror images in the wall. The far views
/// see the wall, the door and the room's middle; the near ones look through the door at the
/// other room's floor, so the doorway's cells are seen empty along rays that end beyond them.
struct View {
  Eigen::Vector3d eye_m, target_m;
};
std::vector<View> roomAViews() {
  const double yc = kDoorCentreY_m;
  return {
      {{-3.5, 0.0, 1.3}, {0.0, yc, 0.6}},     // straight at the door
      {{-3.5, -1.2, 1.3}, {0.0, yc, 0.6}},    // at the door from the sides
      {{-3.5, 1.2, 1.3}, {0.0, yc, 0.6}},     //
      {{-1.8, -0.9, 1.4}, {2.0, 0.7, 0.2}},   // through the door, at room B's floor
      {{-1.8, 0.9, 1.4}, {2.0, -0.7, 0.2}},   //
      {{-2.6, 0.2, 1.4}, {0.8, yc, 0.0}},     // down at the doorway's floor
      {{-3.2, -1.6, 1.2}, {-0.6, 1.2, 0.4}},  // across room A, for its middle and the wall
      {{-3.2, 1.6, 1.2}, {-0.6, -1.2, 0.4}},  //
  };
}

struct GridCell {
  int x = 0, y = 0;
};

Eigen::Vector2d cellCentre(const OccupancyGrid2D& grid, int x, int y) {
  return {grid.origin_x_m + (x + 0.5) * grid.resolution_m,
          grid.origin_y_m + (y + 0.5) * grid.resolution_m};
}

bool cellAt(const OccupancyGrid2D& grid, const Eigen::Vector2d& p_m, GridCell* cell) {
  cell->x = static_cast<int>(std::floor((p_m.x() - grid.origin_x_m) / grid.resolution_m));
  cell->y = static_cast<int>(std::floor((p_m.y() - grid.origin_y_m) / grid.resolution_m));
  return cell->x >= 0 && cell->y >= 0 && cell->x < grid.width && cell->y < grid.height;
}

/// Per cell, whether a robot of `radius_m` may stand there: the cell is free and no occupied
/// cell's centre lies within the radius of its centre (costmap_2d's inscribed inflation).
/// Unknown cells are not traversable: a planner must not drive into space nobody saw.
std::vector<bool> traversable(const OccupancyGrid2D& grid, double radius_m) {
  std::vector<bool> out(grid.cells.size(), false);
  const int reach = static_cast<int>(std::ceil(radius_m / grid.resolution_m));
  const double reach2 = (radius_m / grid.resolution_m) * (radius_m / grid.resolution_m);
  for (int y = 0; y < grid.height; ++y)
    for (int x = 0; x < grid.width; ++x) {
      if (grid.at(x, y) != OccupancyGrid2D::kFree) continue;
      bool clear = true;
      for (int dy = -reach; dy <= reach && clear; ++dy)
        for (int dx = -reach; dx <= reach && clear; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= grid.width || ny >= grid.height) continue;
          if (dx * dx + dy * dy <= reach2 && grid.at(nx, ny) == OccupancyGrid2D::kOccupied)
            clear = false;
        }
      out[static_cast<size_t>(y) * grid.width + x] = clear;
    }
  return out;
}

/// A* on the 8-connected grid with Euclidean step costs and heuristic: the cells from `start`
/// to `goal` (both included), empty if no path exists.
std::vector<GridCell> aStar(const OccupancyGrid2D& grid, const std::vector<bool>& free,
                            GridCell start, GridCell goal) {
  const auto index = [&](int x, int y) { return static_cast<size_t>(y) * grid.width + x; };
  const auto heuristic = [&](int x, int y) { return std::hypot(x - goal.x, y - goal.y); };
  std::vector<double> cost(grid.cells.size(), std::numeric_limits<double>::infinity());
  std::vector<size_t> parent(grid.cells.size(), std::numeric_limits<size_t>::max());
  using Entry = std::pair<double, size_t>;  // (cost so far + heuristic, cell)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  cost[index(start.x, start.y)] = 0.0;
  open.push({heuristic(start.x, start.y), index(start.x, start.y)});
  const size_t goal_index = index(goal.x, goal.y);
  while (!open.empty()) {
    const auto [f, current] = open.top();
    open.pop();
    const int x = static_cast<int>(current % grid.width),
              y = static_cast<int>(current / grid.width);
    if (f > cost[current] + heuristic(x, y) + 1e-9) continue;  // a stale entry
    if (current == goal_index) break;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= grid.width || ny >= grid.height)
          continue;
        const size_t next = index(nx, ny);
        if (!free[next]) continue;
        const double c = cost[current] + std::hypot(dx, dy);
        if (c < cost[next]) {
          cost[next] = c;
          parent[next] = current;
          open.push({c + heuristic(nx, ny), next});
        }
      }
  }
  std::vector<GridCell> path;
  if (!std::isfinite(cost[goal_index])) return path;
  for (size_t c = goal_index; c != std::numeric_limits<size_t>::max(); c = parent[c])
    path.push_back({static_cast<int>(c % grid.width), static_cast<int>(c / grid.width)});
  std::reverse(path.begin(), path.end());
  return path;
}

/// The grid around the doorway, +y up: '#' occupied, '.' free and traversable for `free`,
/// ',' free but within the robot radius of an obstacle, ' ' unknown, '*' on `path`.
std::string doorwayAscii(const OccupancyGrid2D& grid, const std::vector<bool>& free,
                         const std::vector<GridCell>& path) {
  std::vector<char> on_path(grid.cells.size(), 0);
  for (const GridCell& c : path) on_path[static_cast<size_t>(c.y) * grid.width + c.x] = 1;
  GridCell low, high;
  cellAt(grid, {-0.8, kDoorCentreY_m - 1.0}, &low);
  cellAt(grid, {0.8, kDoorCentreY_m + 1.0}, &high);
  std::ostringstream out;
  out << "grid around the doorway (x " << -0.8 << ".." << 0.8 << " m left to right, y "
      << kDoorCentreY_m + 1.0 << ".." << kDoorCentreY_m - 1.0 << " m top to bottom):\n";
  for (int y = std::min(high.y, grid.height - 1); y >= std::max(low.y, 0); --y) {
    out << "  ";
    for (int x = std::max(low.x, 0); x <= std::min(high.x, grid.width - 1); ++x) {
      const size_t i = static_cast<size_t>(y) * grid.width + x;
      const int8_t v = grid.cells[i];
      out << (on_path[i]                        ? '*'
              : v == OccupancyGrid2D::kOccupied ? '#'
              : v == OccupancyGrid2D::kUnknown  ? ' '
              : free[i]                         ? '.'
                                                : ',');
    }
    out << "  y " << cellCentre(grid, 0, y).y() << "\n";
  }
  return out.str();
}

bool onWallLine(const Eigen::Vector2d& centre_m, double cell_m) {
  // The cell's x span overlaps the wall's thickness.
  return std::abs(centre_m.x()) < kWallHalfThickness_m + cell_m / 2;
}

TEST(PlanningDoorway, AnEightyCentimetreDoorStaysPassableForAQuarterMetreRobot) {
  const sim::AnalyticScene scene = twoRoomsScene();
  MapperConfig config;
  config.max_depth_m = 6.0;
  config.mesh_enabled = false;
  Mapper mapper(config);
  std::vector<View> views = roomAViews();
  for (const View& a : roomAViews()) {
    const Eigen::Vector3d mirror(-1.0, 1.0, 1.0);
    views.push_back({a.eye_m.cwiseProduct(mirror), a.target_m.cwiseProduct(mirror)});
  }
  // Quick mode (ThreadSanitizer) keeps the straight views and the ones through the door from
  // each room: the doorway and both middles are still seen twice.
  const std::vector<int> quick = {0, 1, 3, 4, 8, 9, 11, 12};
  const int frames = static_cast<int>(test::quickMode() ? quick.size() : views.size());
  for (int i = 0; i < frames; ++i) {
    const View& v = views[test::quickMode() ? quick[i] : i];
    StereoFrame frame = renderFrame(scene, vgaCamera(), sim::lookAt(v.eye_m, v.target_m),
                                    /*noise_px=*/0.3, /*seed=*/101 + i);
    frame.timestamp_s = 1.0 + i;
    ASSERT_TRUE(mapper.integrate(frame).accepted) << "view " << i;
  }
  mapper.updatePlanning();
  const OccupancyGrid2D grid =
      projectOccupancy(*mapper.planning(), config.grid_min_z_m, config.grid_max_z_m);
  ASSERT_GT(grid.width, 0);
  const double cell_m = grid.resolution_m;

  const double robot_radius_m = 0.25;
  const std::vector<bool> free = traversable(grid, robot_radius_m);
  const auto isFree = [&](const GridCell& c) {
    return free[static_cast<size_t>(c.y) * grid.width + c.x];
  };
  // Off the door's axis, so the route has to turn towards the door and back.
  const Eigen::Vector2d start_m(-2.0, -0.8), goal_m(2.0, 0.8), door_m(0.0, kDoorCentreY_m);
  GridCell start, goal;
  ASSERT_TRUE(cellAt(grid, start_m, &start)) << "room A's middle lies outside the grid";
  ASSERT_TRUE(cellAt(grid, goal_m, &goal)) << "room B's middle lies outside the grid";
  ASSERT_TRUE(isFree(start)) << "the start (room A's middle) is not traversable: state "
                             << int(grid.at(start.x, start.y)) << " (the views missed it?)";
  ASSERT_TRUE(isFree(goal)) << "the goal (room B's middle) is not traversable: state "
                            << int(grid.at(goal.x, goal.y)) << " (the views missed it?)";

  // The wall is there in the grid: every row of the wall line from the jambs out to 1.6 m from
  // the door's axis holds an occupied cell (else a path could go around the door, not through).
  int wall_rows = 0, wall_rows_open = 0;
  for (int y = 0; y < grid.height; ++y) {
    const double row_y_m = cellCentre(grid, 0, y).y();
    const double from_door_m = std::abs(row_y_m - kDoorCentreY_m);
    if (from_door_m < kDoorHalfWidth_m + cell_m || from_door_m > 1.6) continue;
    bool occupied = false;
    for (int x = 0; x < grid.width; ++x)
      occupied |=
          onWallLine(cellCentre(grid, x, y), cell_m) && grid.at(x, y) == OccupancyGrid2D::kOccupied;
    ++wall_rows;
    wall_rows_open += !occupied;
  }
  EXPECT_GE(wall_rows, 2 * 13);  // (1.6 − 0.48) m / 8 cm = 14 rows a side
  EXPECT_EQ(wall_rows_open, 0) << "rows of the wall beside the door without an occupied cell\n"
                               << doorwayAscii(grid, free, {});

  // Doorway cells the robot may stand on: on the wall line, within the door's span.
  int doorway_free = 0;
  for (int y = 0; y < grid.height; ++y)
    for (int x = 0; x < grid.width; ++x)
      doorway_free += onWallLine(cellCentre(grid, x, y), cell_m) &&
                      std::abs(cellCentre(grid, x, y).y() - kDoorCentreY_m) <= kDoorHalfWidth_m &&
                      free[static_cast<size_t>(y) * grid.width + x];

  const std::vector<GridCell> path = aStar(grid, free, start, goal);
  ASSERT_FALSE(path.empty()) << "no path for a " << robot_radius_m << " m robot\n"
                             << doorwayAscii(grid, free, path);
  double length_m = 0.0;
  int wall_cells = 0;
  for (size_t i = 0; i < path.size(); ++i) {
    const Eigen::Vector2d c = cellCentre(grid, path[i].x, path[i].y);
    if (i > 0) length_m += (c - cellCentre(grid, path[i - 1].x, path[i - 1].y)).norm();
    if (!onWallLine(c, cell_m)) continue;
    ++wall_cells;
    EXPECT_LE(std::abs(c.y() - kDoorCentreY_m), kDoorHalfWidth_m)
        << "the path crosses the wall's line outside the door at y " << c.y();
  }
  // An 8-connected step moves one column at most: crossing the wall means visiting its columns.
  EXPECT_GE(wall_cells, 2);
  const double via_door_m = (door_m - start_m).norm() + (goal_m - door_m).norm();
  EXPECT_LE(length_m, 1.5 * via_door_m) << doorwayAscii(grid, free, path);

  // A robot 0.9 m wide does not fit through the 0.8 m door, and there is no other way.
  const std::vector<bool> wide_free = traversable(grid, 0.45);
  const std::vector<GridCell> wide_path = aStar(grid, wide_free, start, goal);
  EXPECT_TRUE(wide_path.empty()) << "a 0.45 m robot found a path of " << wide_path.size()
                                 << " cells\n"
                                 << doorwayAscii(grid, wide_free, wide_path);

  std::printf(
      "[ doorway ] %d frames: path %.2f m (%zu cells; via the door centre %.2f m), %d doorway "
      "cells traversable at %.2f m radius\n",
      frames, length_m, path.size(), via_door_m, doorway_free, robot_radius_m);
  if (HasFailure()) std::printf("%s", doorwayAscii(grid, free, path).c_str());
}

}  // namespace
}  // namespace stereo_fusion
