// The base station's fleet parameters: robots, robot_node, operator_frame and the costmap's.
#include <gtest/gtest.h>

#include <cmath>

#include "stereo_fusion/ros/FleetConfig.h"

namespace stereo_fusion {
namespace {

/// True when exactly one error is reported and it contains `what`.
::testing::AssertionResult oneErrorNaming(const FleetConfig& config, const std::string& what) {
  const std::vector<std::string> errors = validateFleetConfig(config);
  if (errors.size() != 1)
    return ::testing::AssertionFailure() << errors.size() << " errors, want 1 naming " << what;
  if (errors[0].find(what) == std::string::npos)
    return ::testing::AssertionFailure() << "'" << errors[0] << "' does not name " << what;
  return ::testing::AssertionSuccess();
}

TEST(FleetConfig, DefaultsAreTheSingleRobotAssemblerAndValid) {
  const FleetConfig config;
  EXPECT_FALSE(config.fleet());
  EXPECT_TRUE(validateFleetConfig(config).empty());
  FleetConfig three;
  three.robots = {"robot1", "robot2", "robot_3"};
  EXPECT_TRUE(three.fleet());
  EXPECT_TRUE(validateFleetConfig(three).empty());
  EXPECT_EQ(three.robotNamespace("robot2"), "/robot2/stereo_fusion");
}

TEST(FleetConfig, RefusesRobotNamesThatAreNotOneNameTokenOrRepeat) {
  for (const std::string bad : {"", "1robot", "robot/1", "/robot1", "robot 1", "robot-1"}) {
    FleetConfig config;
    config.robots = {"robot1", bad};
    EXPECT_TRUE(oneErrorNaming(config, "robots: '" + bad + "'")) << bad;
  }
  FleetConfig twice;
  twice.robots = {"robot1", "robot2", "robot1"};
  EXPECT_TRUE(oneErrorNaming(twice, "listed twice"));
}

TEST(FleetConfig, RefusesBadRobotNodeOperatorFrameAndRate) {
  FleetConfig config;
  config.robot_node = "stereo/fusion";
  EXPECT_TRUE(oneErrorNaming(config, "robot_node"));
  config = FleetConfig();
  for (const std::string bad : {"", "/map", "operator map"}) {
    config.operator_frame = bad;
    EXPECT_TRUE(oneErrorNaming(config, "operator_frame")) << "'" << bad << "'";
  }
  config = FleetConfig();
  config.operator_frame = "robot1/map";  // a robot's frame is a valid operator frame
  EXPECT_TRUE(validateFleetConfig(config).empty());
  for (double bad : {-1.0, 100.5, std::nan("")}) {
    config = FleetConfig();
    config.grid_publish_rate_hz = bad;
    EXPECT_TRUE(oneErrorNaming(config, "grid_publish_rate_hz")) << bad;
  }
  config = FleetConfig();
  config.grid_publish_rate_hz = 0.0;  // the fleet costmap off
  EXPECT_TRUE(validateFleetConfig(config).empty());
}

TEST(FleetConfig, RefusesTheCostmapsMergeParameters) {
  FleetConfig config;
  config.grid.resolution_m = 0.0;
  EXPECT_TRUE(oneErrorNaming(config, "resolution_m"));
  config = FleetConfig();
  config.grid.max_cells = 0;
  EXPECT_TRUE(oneErrorNaming(config, "max_cells"));
  config = FleetConfig();
  config.grid.max_tilt_rad = 2.0;
  EXPECT_TRUE(oneErrorNaming(config, "max_tilt_rad"));
}

}  // namespace
}  // namespace stereo_fusion
