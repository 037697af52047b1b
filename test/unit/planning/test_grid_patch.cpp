// GridPatch: the window of new cells a map_msgs/OccupancyGridUpdate carries, applied to a grid
// and computed between two grids.
#include <gtest/gtest.h>

#include <random>

#include "stereo_fusion/planning/GridPatch.h"

namespace stereo_fusion {
namespace {

OccupancyGrid2D unknownGrid(int width, int height) {
  OccupancyGrid2D g;
  g.resolution_m = 0.1;
  g.origin_x_m = -1.0;
  g.origin_y_m = 2.0;
  g.width = width;
  g.height = height;
  g.cells.assign(static_cast<size_t>(width) * height, OccupancyGrid2D::kUnknown);
  return g;
}

TEST(GridPatch, WritesItsWindowRowByRow) {
  OccupancyGrid2D g = unknownGrid(4, 3);
  GridPatch p;
  p.x = 1, p.y = 1, p.width = 2, p.height = 2;
  p.cells = {0, 100, 100, 0};
  std::string error;
  ASSERT_TRUE(applyGridPatch(p, &g, &error)) << error;
  const std::vector<int8_t> want = {-1, -1,  -1,  -1,  //
                                    -1, 0,   100, -1,  //
                                    -1, 100, 0,   -1};
  EXPECT_EQ(g.cells, want);
}

TEST(GridPatch, RefusesWindowsOutsideTheGridOrOfTheWrongSizeAndLeavesItAlone) {
  const OccupancyGrid2D before = unknownGrid(4, 3);
  const auto refused = [&](GridPatch p, const std::string& why) {
    OccupancyGrid2D g = before;
    std::string error;
    EXPECT_FALSE(applyGridPatch(p, &g, &error)) << why;
    EXPECT_FALSE(error.empty()) << why;
    EXPECT_EQ(g.cells, before.cells) << why;
  };
  GridPatch p;
  p.x = 3, p.y = 0, p.width = 2, p.height = 1, p.cells = {0, 0};
  refused(p, "one column past the right edge");
  p.x = 0, p.y = 2, p.width = 1, p.height = 2, p.cells = {0, 0};
  refused(p, "one row past the top");
  p.x = -1, p.y = 0, p.width = 1, p.height = 1, p.cells = {0};
  refused(p, "negative corner");
  p.x = 0, p.y = 0, p.width = 2, p.height = 2, p.cells = {0, 0, 0};
  refused(p, "3 cells for 2 x 2");
}

TEST(GridPatch, ChangeIsTheBoundingWindowOfTheCellsThatDiffer) {
  const OccupancyGrid2D a = unknownGrid(5, 4);
  OccupancyGrid2D b = a;
  const auto equal = gridChange(a, b);
  ASSERT_TRUE(equal);
  EXPECT_TRUE(equal->empty());
  b.cells[1 * 5 + 3] = OccupancyGrid2D::kOccupied;  // (3, 1)
  b.cells[2 * 5 + 1] = OccupancyGrid2D::kFree;      // (1, 2)
  const auto change = gridChange(a, b);
  ASSERT_TRUE(change);
  EXPECT_EQ(change->x, 1);
  EXPECT_EQ(change->y, 1);
  EXPECT_EQ(change->width, 3);
  EXPECT_EQ(change->height, 2);
  const std::vector<int8_t> want = {-1, -1, 100,  //
                                    0,  -1, -1};
  EXPECT_EQ(change->cells, want);
}

TEST(GridPatch, NoChangeBetweenGridsOfDifferentExtent) {
  const OccupancyGrid2D a = unknownGrid(5, 4);
  OccupancyGrid2D b = unknownGrid(5, 5);
  EXPECT_FALSE(gridChange(a, b));
  b = a;
  b.origin_x_m += 0.1;
  EXPECT_FALSE(gridChange(a, b));
  b = a;
  b.resolution_m = 0.2;
  EXPECT_FALSE(gridChange(a, b));
}

TEST(GridPatch, ChangeAppliedToTheOldGridGivesTheNewOne) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> value(0, 2), coin(0, 9);
  const int8_t values[3] = {OccupancyGrid2D::kUnknown, OccupancyGrid2D::kFree,
                            OccupancyGrid2D::kOccupied};
  for (int trial = 0; trial < 50; ++trial) {
    OccupancyGrid2D a = unknownGrid(13, 7);
    for (int8_t& c : a.cells) c = values[value(rng)];
    OccupancyGrid2D b = a;
    for (int8_t& c : b.cells)
      if (coin(rng) == 0) c = values[value(rng)];
    const auto change = gridChange(a, b);
    ASSERT_TRUE(change);
    std::string error;
    if (!change->empty()) ASSERT_TRUE(applyGridPatch(*change, &a, &error)) << error;
    EXPECT_EQ(a.cells, b.cells) << "trial " << trial;
  }
}

}  // namespace
}  // namespace stereo_fusion
