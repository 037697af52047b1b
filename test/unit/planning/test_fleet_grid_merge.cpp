// The fleet costmap's merge (issue 51, item 2): robots' grids placed by their planar poses in the
// operator frame, sampled at the merged cells' centres, combined occupied > free > unknown.
// Grids are written as rows of characters, row 0 (the smallest y) first: 'O' occupied,
// 'F' free, '.' unknown.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "stereo_fusion/planning/FleetGridMerge.h"

namespace stereo_fusion {
namespace {

OccupancyGrid2D grid(double resolution_m, double origin_x_m, double origin_y_m,
                     const std::vector<std::string>& rows) {
  OccupancyGrid2D g;
  g.resolution_m = resolution_m;
  g.origin_x_m = origin_x_m;
  g.origin_y_m = origin_y_m;
  g.height = static_cast<int>(rows.size());
  g.width = rows.empty() ? 0 : static_cast<int>(rows[0].size());
  for (const std::string& row : rows)
    for (char c : row)
      g.cells.push_back(c == 'O'   ? OccupancyGrid2D::kOccupied
                        : c == 'F' ? OccupancyGrid2D::kFree
                                   : OccupancyGrid2D::kUnknown);
  return g;
}

std::vector<std::string> rows(const OccupancyGrid2D& g) {
  std::vector<std::string> out;
  for (int y = 0; y < g.height; ++y) {
    std::string row;
    for (int x = 0; x < g.width; ++x) {
      const int8_t v = g.at(x, y);
      row += v == OccupancyGrid2D::kOccupied ? 'O' : v == OccupancyGrid2D::kFree ? 'F' : '.';
    }
    out.push_back(row);
  }
  return out;
}

PlanarPose pose(double x_m, double y_m, double yaw_rad = 0.0) {
  PlanarPose p;
  p.x_m = x_m;
  p.y_m = y_m;
  p.yaw_rad = yaw_rad;
  return p;
}

FleetGridMerge merger(double resolution_m, int64_t max_cells = 4194304) {
  FleetGridMergeConfig c;
  c.resolution_m = resolution_m;
  c.max_cells = max_cells;
  EXPECT_TRUE(validateFleetGridMergeConfig(c).empty());
  return FleetGridMerge(c);
}

TEST(FleetGridMerge, ConfigValidationNamesEachBadField) {
  EXPECT_TRUE(validateFleetGridMergeConfig({}).empty());
  FleetGridMergeConfig c;
  c.resolution_m = 0.0;
  c.max_cells = 0;
  c.max_tilt_rad = -0.1;
  EXPECT_EQ(validateFleetGridMergeConfig(c).size(), 3u);
  c = {};
  c.resolution_m = NAN;
  ASSERT_EQ(validateFleetGridMergeConfig(c).size(), 1u);
  EXPECT_NE(validateFleetGridMergeConfig(c)[0].find("resolution_m"), std::string::npos);
  c = {};
  c.max_cells = int64_t{1} << 40;  // a terabyte of cells
  EXPECT_EQ(validateFleetGridMergeConfig(c).size(), 1u);
  c = {};
  c.max_tilt_rad = M_PI / 2;
  EXPECT_EQ(validateFleetGridMergeConfig(c).size(), 1u);
}

// Identity poses, the grids' own lattice: the merge of a grid with itself is that grid, cell for
// cell, origin and size included (origin 0.2, -0.1 at 0.1 m: lattice lines, snapped).
TEST(FleetGridMerge, IdentityPosesAndEqualGridsGiveTheGrid) {
  const OccupancyGrid2D a = grid(0.1, 0.2, -0.1, {"OF.", ".FO"});
  const OccupancyGrid2D b = a;
  const FleetGridMergeResult r = merger(0.1).merge({{&a, {}}, {&b, {}}});
  ASSERT_TRUE(r.error.empty()) << r.error;
  EXPECT_EQ(r.robots_merged, 2);
  EXPECT_TRUE(r.robots_refused.empty());
  EXPECT_DOUBLE_EQ(r.grid.resolution_m, 0.1);
  EXPECT_DOUBLE_EQ(r.grid.origin_x_m, 0.2);
  EXPECT_DOUBLE_EQ(r.grid.origin_y_m, -0.1);
  EXPECT_EQ(rows(r.grid), rows(a));
}

// A: 3 free cells at x 0..0.3 m. B: [O F F] in its own frame from x 0, placed 0.2 m along x:
// it covers operator cells 2..4. Cell 2 is A's free and B's occupied → occupied.
TEST(FleetGridMerge, SideBySideOverlapOccupiedWinsOverFree) {
  const OccupancyGrid2D a = grid(0.1, 0.0, 0.0, {"FFF"});
  const OccupancyGrid2D b = grid(0.1, 0.0, 0.0, {"OFF"});
  const FleetGridMergeResult r = merger(0.1).merge({{&a, pose(0, 0)}, {&b, pose(0.2, 0)}});
  ASSERT_TRUE(r.error.empty()) << r.error;
  EXPECT_DOUBLE_EQ(r.grid.origin_x_m, 0.0);
  EXPECT_EQ(rows(r.grid), std::vector<std::string>({"FFOFF"}));
  // And the other way: A occupied where B is free.
  const OccupancyGrid2D a2 = grid(0.1, 0.0, 0.0, {"FFO"});
  const OccupancyGrid2D b2 = grid(0.1, 0.0, 0.0, {"FFF"});
  EXPECT_EQ(rows(merger(0.1).merge({{&a2, pose(0, 0)}, {&b2, pose(0.2, 0)}}).grid),
            std::vector<std::string>({"FFOFF"}));
}

// Every pair of states on one cell: the rule's whole table.
TEST(FleetGridMerge, FreeWinsOverUnknownOccupiedOverBoth) {
  const OccupancyGrid2D a = grid(0.1, 0.0, 0.0, {"...FFFOOO"});
  const OccupancyGrid2D b = grid(0.1, 0.0, 0.0, {".FO.FO.FO"});
  const FleetGridMergeResult r = merger(0.1).merge({{&a, {}}, {&b, {}}});
  EXPECT_EQ(rows(r.grid), std::vector<std::string>({".FOFFOOOO"}));
  // Probabilities (1..99, which OccupancyGrid allows) count as occupied: the conservative side.
  OccupancyGrid2D p = grid(0.1, 0.0, 0.0, {"FF"});
  p.cells[1] = 30;
  EXPECT_EQ(rows(merger(0.1).merge({{&p, {}}}).grid), std::vector<std::string>({"FO"}));
}

// A 3 x 2 grid of 0.5 m cells rotated +90° about the operator origin: robot (x, y) → operator
// (−y, x), footprint x [−1, 0], y [0, 1.5] → 2 x 3 cells from (−1, 0). Operator cell (i, j)'s
// centre ((i − 1.5) 0.5, (j + 0.5) 0.5) carried back by Rᵀ(x, y) = (y, −x) is
// ((j + 0.5) 0.5, (1.5 − i) 0.5): robot cell (j, 1 − i).
//   robot row 0: O F F          operator row 0: robot (0,1) (0,0) = . O
//   robot row 1: . O .          operator row 1: robot (1,1) (1,0) = O F
//                               operator row 2: robot (2,1) (2,0) = . F
TEST(FleetGridMerge, QuarterTurnMovesEachCellWhereTheRotationSays) {
  const OccupancyGrid2D a = grid(0.5, 0.0, 0.0, {"OFF", ".O."});
  const FleetGridMergeResult r = merger(0.5).merge({{&a, pose(0, 0, M_PI / 2)}});
  ASSERT_TRUE(r.error.empty()) << r.error;
  EXPECT_DOUBLE_EQ(r.grid.origin_x_m, -1.0);
  EXPECT_DOUBLE_EQ(r.grid.origin_y_m, 0.0);
  EXPECT_EQ(r.grid.width, 2);
  EXPECT_EQ(r.grid.height, 3);
  EXPECT_EQ(rows(r.grid), std::vector<std::string>({".O", "OF", ".F"}));
  // The same from a 3D alignment: a yaw of 90° and a 2 m lift (dropped) give the same grid.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.rotate(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  T.translation() = Eigen::Vector3d(0, 0, 2.0);
  const PlanarPose p = planarPose(T);
  EXPECT_NEAR(p.yaw_rad, M_PI / 2, 1e-12);
  EXPECT_NEAR(p.tilt_rad, 0.0, 1e-12);
  EXPECT_EQ(rows(merger(0.5).merge({{&a, p}}).grid), rows(r.grid));
}

// [O F . O] at 0.1 m placed (0.13, −0.27): footprint x [0.13, 0.53], y [−0.27, −0.17] → columns
// floor(1.3) = 1 .. ceil(5.3) = 6, rows floor(−2.7) = −3 .. ceil(−1.7) = −1: 5 x 2 cells from
// (0.1, −0.3). Column gi's centre (gi + 0.5) 0.1 is robot x (gi − 0.8) cells: robot cell gi − 1
// for gi 1..4, and 4.2 (outside: unknown) for gi 5, though the cell overlaps the robot's last
// cell by 0.3 of its width. Row −3's centre −0.25 is robot y 0.2 cells (row 0); row −2's, 1.2
// (outside).
TEST(FleetGridMerge, NonIntegerTranslationSamplesAtTheCentres) {
  const OccupancyGrid2D a = grid(0.1, 0.0, 0.0, {"OF.O"});
  const FleetGridMergeResult r = merger(0.1).merge({{&a, pose(0.13, -0.27)}});
  ASSERT_TRUE(r.error.empty()) << r.error;
  EXPECT_NEAR(r.grid.origin_x_m, 0.1, 1e-12);
  EXPECT_NEAR(r.grid.origin_y_m, -0.3, 1e-12);
  EXPECT_EQ(rows(r.grid), std::vector<std::string>({"OF.O.", "....."}));
  // Shifted 0.17 instead: centres at robot x gi − 1.2 → robot cell gi − 2 for gi 2..5; column 1's
  // centre −0.2 is outside. Footprint [1.7, 5.7] → columns 1..5.
  const FleetGridMergeResult s = merger(0.1).merge({{&a, pose(0.17, -0.27)}});
  EXPECT_NEAR(s.grid.origin_x_m, 0.1, 1e-12);
  EXPECT_EQ(rows(s.grid), std::vector<std::string>({".OF.O", "....."}));
}

// A finer robot grid (0.125 m) into 0.25 m cells (both exact in binary): each operator centre
// lands on a robot cell corner ((0.125, 0.125) is robot (1, 1) exactly) and takes the cell above
// it on both axes, by floor: robot row 1, cells 1 and 3, not row 0's cells 0 and 2.
TEST(FleetGridMerge, CentreOnARobotCellEdgeTakesTheCellAbove) {
  const OccupancyGrid2D a = grid(0.125, 0.0, 0.0, {"FFFF", "FOFO"});
  const FleetGridMergeResult r = merger(0.25).merge({{&a, {}}});
  EXPECT_EQ(rows(r.grid), std::vector<std::string>({"OO"}));
}

// 10 x 10 cells allowed, 100 cells: at the limit it merges; shifted half a cell the footprint
// covers 11 x 11 and the merge is refused, saying how large it would be. A robot 10 km away
// (an alignment gone wrong: 1e4 m / 0.1 m + 10 cells a side) is refused the same way, before
// anything is allocated.
TEST(FleetGridMerge, MoreCellsThanTheLimitIsRefused) {
  const OccupancyGrid2D a = grid(0.1, 0.0, 0.0, std::vector<std::string>(10, "FFFFFFFFFF"));
  const FleetGridMerge merge = merger(0.1, 100);
  FleetGridMergeResult r = merge.merge({{&a, {}}});
  EXPECT_TRUE(r.error.empty()) << r.error;
  EXPECT_EQ(r.grid.cells.size(), 100u);
  r = merge.merge({{&a, pose(0.05, 0.05)}});
  EXPECT_NE(r.error.find("11 x 11"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("max_cells 100"), std::string::npos) << r.error;
  EXPECT_TRUE(r.grid.cells.empty());
  EXPECT_EQ(r.robots_merged, 0);
  const FleetGridMergeResult far = merger(0.1).merge({{&a, {}}, {&a, pose(1e4, 1e4)}});
  EXPECT_NE(far.error.find("100010 x 100010"), std::string::npos) << far.error;
  EXPECT_TRUE(far.grid.cells.empty());
}

// A bad robot is left out, named, and the others merged; a grid with no cells is counted apart.
TEST(FleetGridMerge, BadRobotsAreRefusedByNameAndTheRestMerged) {
  const OccupancyGrid2D good = grid(0.1, 0.0, 0.0, {"OF"});
  OccupancyGrid2D short_cells = good;
  short_cells.cells.pop_back();
  const OccupancyGrid2D empty = grid(0.1, 0.0, 0.0, {});
  Eigen::Isometry3d tilted = Eigen::Isometry3d::Identity();
  tilted.rotate(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()));  // 0.2 rad roll
  const PlanarPose tilted_pose = planarPose(tilted);
  EXPECT_NEAR(tilted_pose.tilt_rad, 0.2, 1e-12);
  EXPECT_NEAR(tilted_pose.yaw_rad, 0.0, 1e-12);
  const FleetGridMergeResult r = merger(0.1).merge({{&good, {}},
                                                    {&short_cells, {}},
                                                    {&good, pose(NAN, 0)},
                                                    {&empty, {}},
                                                    {&good, tilted_pose},
                                                    {nullptr, {}}});
  EXPECT_TRUE(r.error.empty()) << r.error;
  EXPECT_EQ(r.robots_merged, 1);
  EXPECT_EQ(r.robots_empty, 1);
  ASSERT_EQ(r.robots_refused.size(), 4u);
  EXPECT_EQ(r.robots_refused[0].message().rfind("robot 1: its grid holds 1 cells", 0), 0u)
      << r.robots_refused[0].message();
  EXPECT_EQ(r.robots_refused[1].message().rfind("robot 2: its pose", 0), 0u)
      << r.robots_refused[1].message();
  EXPECT_EQ(r.robots_refused[2].message().rfind("robot 4: its map frame is tilted 0.2", 0), 0u)
      << r.robots_refused[2].message();
  EXPECT_EQ(r.robots_refused[3].message(), "robot 5: no grid");
  EXPECT_EQ(rows(r.grid), std::vector<std::string>({"OF"}));
  // Nothing mergeable: an empty grid, no error.
  const FleetGridMergeResult none = merger(0.1).merge({{&empty, {}}});
  EXPECT_TRUE(none.error.empty());
  EXPECT_EQ(none.grid.width, 0);
  EXPECT_TRUE(none.grid.cells.empty());
}

OccupancyGrid2D randomGrid(std::mt19937* rng, double resolution_m, int width, int height) {
  OccupancyGrid2D g;
  g.resolution_m = resolution_m;
  std::uniform_real_distribution<double> origin(-1.0, 1.0);
  g.origin_x_m = origin(*rng);
  g.origin_y_m = origin(*rng);
  g.width = width;
  g.height = height;
  const int8_t values[3] = {OccupancyGrid2D::kUnknown, OccupancyGrid2D::kFree,
                            OccupancyGrid2D::kOccupied};
  std::uniform_int_distribution<int> pick(0, 2);
  for (int i = 0; i < width * height; ++i) g.cells.push_back(values[pick(*rng)]);
  return g;
}

// Three overlapping robots at odd yaws and resolutions: every one of the 6 orders gives the
// same grid. And each cell holds what a brute-force reading of the rule gives for it.
TEST(FleetGridMerge, ResultDoesNotDependOnTheRobotsOrder) {
  std::mt19937 rng(51);
  const OccupancyGrid2D g0 = randomGrid(&rng, 0.1, 23, 17);
  const OccupancyGrid2D g1 = randomGrid(&rng, 0.05, 31, 40);
  const OccupancyGrid2D g2 = randomGrid(&rng, 0.2, 9, 12);
  std::vector<FleetGridInput> robots = {
      {&g0, pose(0.3, -0.2, 0.4)}, {&g1, pose(-0.5, 0.7, -2.3)}, {&g2, pose(0.1, 0.05, 3.0)}};
  const FleetGridMerge merge = merger(0.07);
  const FleetGridMergeResult first = merge.merge(robots);
  ASSERT_TRUE(first.error.empty()) << first.error;
  ASSERT_EQ(first.robots_merged, 3);
  std::vector<int> order = {0, 1, 2};
  int orders = 0;
  do {
    std::vector<FleetGridInput> permuted;
    for (int k : order) permuted.push_back(robots[k]);
    const FleetGridMergeResult r = merge.merge(permuted);
    EXPECT_EQ(r.grid.origin_x_m, first.grid.origin_x_m);
    EXPECT_EQ(r.grid.origin_y_m, first.grid.origin_y_m);
    EXPECT_EQ(r.grid.cells, first.grid.cells);
    ++orders;
  } while (std::next_permutation(order.begin(), order.end()));
  EXPECT_EQ(orders, 6);
  // The rule, read directly (Eigen's rotation, not the merge's arithmetic) at cell centres
  // away from robot cell edges (a 10⁻⁶ cell tolerance would go either way).
  const OccupancyGrid2D& m = first.grid;
  int checked = 0, occupied = 0;
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) {
      const Eigen::Vector2d c(m.origin_x_m + (x + 0.5) * 0.07, m.origin_y_m + (y + 0.5) * 0.07);
      int best = -1;
      bool ambiguous = false;
      for (const FleetGridInput& in : robots) {
        const Eigen::Vector2d p =
            Eigen::Rotation2Dd(in.T_operator_robot.yaw_rad).inverse() *
            (c - Eigen::Vector2d(in.T_operator_robot.x_m, in.T_operator_robot.y_m));
        const double u = (p.x() - in.grid->origin_x_m) / in.grid->resolution_m;
        const double v = (p.y() - in.grid->origin_y_m) / in.grid->resolution_m;
        const auto nearEdge = [](double t) { return std::abs(t - std::round(t)) < 1e-6; };
        if (nearEdge(u) || nearEdge(v)) ambiguous = true;
        if (u < 0 || v < 0 || u >= in.grid->width || v >= in.grid->height) continue;
        const int8_t val = in.grid->at(static_cast<int>(u), static_cast<int>(v));
        best = std::max(best, val < 0 ? 0 : val == 0 ? 1 : 2);
      }
      if (ambiguous) continue;
      const int8_t expect = best == 2   ? OccupancyGrid2D::kOccupied
                            : best == 1 ? OccupancyGrid2D::kFree
                                        : OccupancyGrid2D::kUnknown;
      EXPECT_EQ(m.at(x, y), expect) << x << ", " << y;
      ++checked;
      occupied += expect == OccupancyGrid2D::kOccupied;
    }
  EXPECT_GT(checked, m.width * m.height * 9 / 10);
  EXPECT_GT(occupied, 100);
}

// The incremental form: robot 1 inside robot 0's footprint changes its cells and moves; the
// window changedWindow() gives, re-merged, equals a full merge (same bounds: robot 0 sets them).
// A move that leaves the bounds asks for a full merge.
TEST(FleetGridMerge, RemergingTheChangedWindowEqualsAFullMerge) {
  std::mt19937 rng(7);
  OccupancyGrid2D big = randomGrid(&rng, 0.1, 60, 50);
  OccupancyGrid2D small_before = randomGrid(&rng, 0.05, 10, 8);
  OccupancyGrid2D small_after = randomGrid(&rng, 0.05, 12, 9);
  for (OccupancyGrid2D* g : {&big, &small_before, &small_after}) g->origin_x_m = g->origin_y_m = 0;
  const FleetGridInput before{&small_before, pose(1.0, 1.5, 0.3)};
  const FleetGridInput after{&small_after, pose(1.4, 1.1, -0.6)};
  const FleetGridMerge merge = merger(0.1);
  OccupancyGrid2D merged = merge.merge({{&big, {}}, before}).grid;
  const FleetGridMergeResult full = merge.merge({{&big, {}}, after});
  ASSERT_EQ(full.grid.width, merged.width);
  ASSERT_EQ(full.grid.height, merged.height);
  ASSERT_NE(full.grid.cells, merged.cells);  // the change shows
  const std::optional<GridCellWindow> window = merge.changedWindow(before, after, merged);
  ASSERT_TRUE(window.has_value());
  EXPECT_LT((window->x1 - window->x0) * (window->y1 - window->y0),
            merged.width * merged.height / 4);
  merge.remergeWindow({{&big, {}}, after}, *window, &merged);
  EXPECT_EQ(merged.cells, full.grid.cells);
  // Moved to 20 m: outside the bounds.
  EXPECT_FALSE(merge.changedWindow(before, {&small_after, pose(20.0, 0.0)}, merged).has_value());
}

}  // namespace
}  // namespace stereo_fusion
