// The occupancy grid's projection and its bound (grid_max_cells): a map whose known columns
// span more than the bound gives a window around the camera, never an allocation of its whole
// extent.
#include <gtest/gtest.h>

#include "stereo_fusion/planning/OccupancyGrid2D.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {
namespace {

/// Marks planning cell (x, y, z) seen free.
void seeFree(PlanningMap* planning, const CellIndex& cell) {
  PlanningBlock::Bits bits{};
  PlanningBlock::set(&bits, cellInBlock(cell), true);
  planning->addSeenFree({{planningBlockOf(cell), bits}});
}

PlanningConfig cells20cm() {
  PlanningConfig c;
  c.cell_m = 0.2;
  c.voxels_per_cell = 1;
  return c;
}

// Hand-worked: free columns x 0..99 on one row (cell z 2: centre 0.5 m, inside the 0.1–1.5 m
// band): 100 cells. Bound 49 cells → a side of 7; the camera over x cell 98 → the window's first
// column is 98 − 3 = 95, slid back to 93 so it stays inside the known 0..99: columns 93..99. The
// row is narrower than the side: kept whole.
TEST(OccupancyGrid, AWideMapGivesAWindowAroundTheCameraInsideTheKnownExtent) {
  ThreadPool pool(1);
  PlanningMap planning(cells20cm(), &pool);
  for (int x = 0; x < 100; ++x) seeFree(&planning, {x, 0, 2});
  const OccupancyGrid2D whole = projectOccupancy(planning, 0.1, 1.5);
  EXPECT_FALSE(whole.windowed);
  EXPECT_EQ(whole.width, 100);
  GridWindow window;
  window.max_cells = 49;
  window.centre_m = {98.5 * 0.2, 0.1};
  const OccupancyGrid2D part = projectOccupancy(planning, 0.1, 1.5, window);
  EXPECT_TRUE(part.windowed);
  EXPECT_EQ(part.known_width, 100);
  EXPECT_EQ(part.known_height, 1);
  EXPECT_EQ(part.width, 7);
  EXPECT_EQ(part.height, 1);
  EXPECT_DOUBLE_EQ(part.origin_x_m, 93 * 0.2);
  for (int x = 0; x < part.width; ++x) EXPECT_EQ(part.at(x, 0), OccupancyGrid2D::kFree) << x;
  // At the bound nothing changes (100 cells, 100 allowed).
  window.max_cells = 100;
  EXPECT_FALSE(projectOccupancy(planning, 0.1, 1.5, window).windowed);
}

// A map 10 km wide at 20 cm cells (known corners 50 000 cells apart on both axes: 2.5·10⁹ cells,
// 2.5 GB as one grid) with the default bound gives 2048 × 2048 cells around the camera.
TEST(OccupancyGrid, AMapTenKilometresWideIsBounded) {
  ThreadPool pool(1);
  PlanningMap planning(cells20cm(), &pool);
  seeFree(&planning, {0, 0, 2});
  seeFree(&planning, {50000, 50000, 2});
  GridWindow window;
  window.max_cells = MapperConfig{}.grid_max_cells;
  window.centre_m = {10000.0, 10000.0};  // the camera at the far corner
  const OccupancyGrid2D grid = projectOccupancy(planning, 0.1, 1.5, window);
  EXPECT_TRUE(grid.windowed);
  EXPECT_EQ(grid.known_width, 50001);
  EXPECT_EQ(grid.width, 2048);
  EXPECT_EQ(grid.height, 2048);
  EXPECT_EQ(grid.cells.size(), size_t{2048} * 2048);
  // The far corner's column is in it (the window slid inside the extent), the origin's is not.
  EXPECT_EQ(grid.at(grid.width - 1, grid.height - 1), OccupancyGrid2D::kFree);
  EXPECT_DOUBLE_EQ(grid.origin_x_m, (50000 - 2047) * 0.2);
}

}  // namespace
}  // namespace stereo_fusion
