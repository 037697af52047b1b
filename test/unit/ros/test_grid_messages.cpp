// nav_msgs/OccupancyGrid and map_msgs/OccupancyGridUpdate ↔ OccupancyGrid2D / GridPatch (no
// master: the messages are plain structs).
#include <gtest/gtest.h>

#include <cmath>

#include "stereo_fusion/ros/GridMessages.h"

namespace stereo_fusion {
namespace {

OccupancyGrid2D smallGrid() {
  OccupancyGrid2D g;
  g.resolution_m = 0.08;
  g.origin_x_m = -1.28;
  g.origin_y_m = 0.64;
  g.width = 3;
  g.height = 2;
  g.cells = {-1, 0, 100, 100, 0, -1};
  return g;
}

TEST(GridMessages, GridRoundTripsThroughTheMessage) {
  const OccupancyGrid2D g = smallGrid();
  const nav_msgs::OccupancyGrid msg = toGridMessage(g, "robot1/map", ros::Time(5.0));
  EXPECT_EQ(msg.header.frame_id, "robot1/map");
  EXPECT_EQ(msg.info.width, 3u);
  EXPECT_EQ(msg.info.origin.orientation.w, 1.0);
  OccupancyGrid2D back;
  std::string error;
  ASSERT_TRUE(fromGridMessage(msg, &back, &error)) << error;
  EXPECT_EQ(back.resolution_m, static_cast<double>(0.08f));  // the message holds a float32
  EXPECT_EQ(back.origin_x_m, -1.28);
  EXPECT_EQ(back.origin_y_m, 0.64);
  EXPECT_EQ(back.width, 3);
  EXPECT_EQ(back.height, 2);
  EXPECT_EQ(back.cells, g.cells);
}

TEST(GridMessages, RefusesGridsItCannotPlaceAndKeepsTheOldOne) {
  const nav_msgs::OccupancyGrid good = toGridMessage(smallGrid(), "m", ros::Time(1.0));
  const auto refused = [&](const nav_msgs::OccupancyGrid& msg, const std::string& what) {
    OccupancyGrid2D held = smallGrid();
    held.cells[0] = 100;
    const OccupancyGrid2D before = held;
    std::string error;
    EXPECT_FALSE(fromGridMessage(msg, &held, &error)) << what;
    EXPECT_NE(error.find(what), std::string::npos) << error;
    EXPECT_EQ(held.cells, before.cells);
    EXPECT_EQ(held.width, before.width);
  };
  nav_msgs::OccupancyGrid msg = good;
  msg.data.pop_back();
  refused(msg, "not width x height");
  msg = good;
  msg.info.resolution = 0.0f;
  refused(msg, "resolution");
  msg = good;
  msg.info.origin.position.x = NAN;
  refused(msg, "origin is not finite");
  msg = good;
  msg.info.origin.orientation.z = std::sin(0.1);
  msg.info.origin.orientation.w = std::cos(0.1);
  refused(msg, "rotated");
}

TEST(GridMessages, PatchRoundTripsThroughTheUpdate) {
  GridPatch p;
  p.x = 4, p.y = 7, p.width = 2, p.height = 1, p.cells = {0, 100};
  const map_msgs::OccupancyGridUpdate msg = toGridUpdateMessage(p, "operator", ros::Time(2.0));
  EXPECT_EQ(msg.header.frame_id, "operator");
  GridPatch back;
  std::string error;
  ASSERT_TRUE(fromGridUpdateMessage(msg, &back, &error)) << error;
  EXPECT_EQ(back.x, 4);
  EXPECT_EQ(back.y, 7);
  EXPECT_EQ(back.width, 2);
  EXPECT_EQ(back.height, 1);
  EXPECT_EQ(back.cells, p.cells);
  map_msgs::OccupancyGridUpdate huge = msg;
  huge.width = 0x80000000u;
  EXPECT_FALSE(fromGridUpdateMessage(huge, &back, &error));
}

}  // namespace
}  // namespace stereo_fusion
