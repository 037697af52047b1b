#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "stereo_fusion/util/RateSchedule.h"

namespace stereo_fusion {
namespace {

TEST(RateSchedule, EachSendIsDueOnePeriodAfterThePreviousWasDue) {
  RateSchedule schedule(10.0);     // 100 ms
  EXPECT_TRUE(schedule.due(5.0));  // the first chance sends
  schedule.sent(5.0);
  EXPECT_FALSE(schedule.due(5.099));
  EXPECT_TRUE(schedule.due(5.1));
  schedule.sent(5.13);  // 30 ms late: the next is still due at 5.2, not 5.23
  EXPECT_FALSE(schedule.due(5.199));
  EXPECT_TRUE(schedule.due(5.2));
  schedule.sent(5.27);  // 70 ms late (more than half a period): again from here, at 5.37
  EXPECT_FALSE(schedule.due(5.36));
  EXPECT_TRUE(schedule.due(5.37));
}

TEST(RateSchedule, ASendThatMayWaitIsPutOffAtMostAPeriod) {
  RateSchedule schedule(10.0);
  schedule.sent(1.0);  // next due at 1.1
  EXPECT_TRUE(schedule.due(1.15));
  EXPECT_FALSE(schedule.due(1.15, true));
  EXPECT_FALSE(schedule.due(1.199, true));
  EXPECT_TRUE(schedule.due(1.2001, true));
}

TEST(RateSchedule, ZeroRateIsAlwaysDue) {
  RateSchedule schedule(0.0);
  EXPECT_TRUE(schedule.due(1.0));
  schedule.sent(1.0);
  EXPECT_TRUE(schedule.due(1.0));
  EXPECT_TRUE(schedule.due(1.0, true));
}

// Frames every 1/30 s, done 5–25 ms after they arrive, a send at 10 Hz when a frame is done:
// 100 sends in 10 s (counting from the send: 300 / 4 to 300 / 3), none closer than half a period.
TEST(RateSchedule, SendsFromLateChancesKeepTheRate) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> done_after_s(0.005, 0.025);
  RateSchedule schedule(10.0);
  std::vector<double> sends;
  for (int frame = 0; frame < 300; ++frame) {
    const double now_s = frame / 30.0 + done_after_s(random);
    if (!schedule.due(now_s)) continue;
    schedule.sent(now_s);
    sends.push_back(now_s);
  }
  EXPECT_GE(sends.size(), 99u);
  EXPECT_LE(sends.size(), 101u);
  for (size_t k = 1; k < sends.size(); ++k) EXPECT_GE(sends[k] - sends[k - 1], 0.05);
}

}  // namespace
}  // namespace stereo_fusion
