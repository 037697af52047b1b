#include <gtest/gtest.h>

#include "stereo_fusion/ros/RecentStamps.h"

using namespace stereo_fusion;

TEST(RecentStamps, TheFirstMessageOfAnUnmatchedStampPassesAndRepeatsAreHeldBack) {
  RecentStamps stamps(3);
  EXPECT_TRUE(stamps.pass(100));
  EXPECT_FALSE(stamps.pass(100)) << "the same stamp while its frame is incomplete";
  EXPECT_TRUE(stamps.pass(200));
  EXPECT_TRUE(stamps.pass(50)) << "an older stamp not held passes (the frame gate judges order)";
  EXPECT_FALSE(stamps.pass(100)) << "still among the last 3";
  EXPECT_TRUE(stamps.pass(300));  // 100 leaves the window: the synchroniser gave up on it too
  EXPECT_TRUE(stamps.pass(100));
  EXPECT_FALSE(stamps.pass(300));
}

TEST(RecentStamps, AMatchedStampIsForgottenSoARepeatIsANewFrame) {
  RecentStamps stamps(4);
  EXPECT_TRUE(stamps.pass(10));
  EXPECT_TRUE(stamps.pass(20));
  stamps.forget(10);
  EXPECT_TRUE(stamps.pass(10)) << "the repeat of a matched frame goes on to the frame gate";
  EXPECT_FALSE(stamps.pass(20));
  stamps.forget(99);  // never passed: nothing happens
  EXPECT_FALSE(stamps.pass(10));
}

TEST(RecentStamps, AWindowOfZeroStillHoldsTheLastStamp) {
  RecentStamps stamps(0);
  EXPECT_TRUE(stamps.pass(7));
  EXPECT_FALSE(stamps.pass(7));
  EXPECT_TRUE(stamps.pass(8));
  EXPECT_TRUE(stamps.pass(7));
}
