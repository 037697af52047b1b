// StageScope and StageMonitor: what a Mapper is doing, readable from a watchdog's thread.
#include <gtest/gtest.h>

#include "../session/SessionTestSupport.h"
#include "stereo_fusion/Mapper.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

TEST(StageScope, NestedStagesGiveTheOuterOneBackAndIdleEndsTheBusyTime) {
  StageMonitor monitor;
  EXPECT_EQ(monitor.busySeconds(), 0.0);
  {
    StageScope outer(&monitor, MapperStage::kValidate);
    EXPECT_EQ(monitor.stage.load(), MapperStage::kValidate);
    EXPECT_NE(monitor.busy_since_ns.load(), 0);
    outer.enter(MapperStage::kFusion);
    {
      StageScope inner(&monitor, MapperStage::kMeshing);
      EXPECT_EQ(monitor.stage.load(), MapperStage::kMeshing);
    }
    EXPECT_EQ(monitor.stage.load(), MapperStage::kFusion);
    EXPECT_NE(monitor.busy_since_ns.load(), 0);
  }
  EXPECT_EQ(monitor.stage.load(), MapperStage::kIdle);
  EXPECT_EQ(monitor.busy_since_ns.load(), 0);
  // A Mapper reports into its monitor and is idle between operations.
  Mapper mapper(sessionTestConfig());
  mapper.setStageMonitor(&monitor);
  ASSERT_TRUE(mapper.integrate(driftingFrame(0)).accepted);
  EXPECT_EQ(monitor.stage.load(), MapperStage::kIdle);
  EXPECT_STREQ(mapperStageName(MapperStage::kLookup), "lookup");
}
