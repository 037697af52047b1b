#include <gtest/gtest.h>

#include "stereo_fusion/ros/SequenceGaps.h"

using namespace stereo_fusion;

TEST(SequenceGaps, CountsTheNumbersSkippedBetweenConsecutiveMessages) {
  SequenceGaps gaps;
  EXPECT_EQ(gaps.next(1), 0u);  // the first numbered message: nothing before it is known
  EXPECT_EQ(gaps.next(2), 0u);
  EXPECT_EQ(gaps.next(5), 2u);  // 3 and 4 were lost
  EXPECT_EQ(gaps.next(6), 0u);
  EXPECT_EQ(gaps.next(16), 9u);
}

TEST(SequenceGaps, UnnumberedStreamsRestartsAndForeignNumbersCountNothing) {
  SequenceGaps gaps;
  for (int i = 0; i < 5; ++i) EXPECT_EQ(gaps.next(0), 0u) << "roscpp leaves seq at 0";
  EXPECT_EQ(gaps.next(7), 0u);
  EXPECT_EQ(gaps.next(7), 0u) << "a repeated number is not a gap";
  EXPECT_EQ(gaps.next(3), 0u) << "the publisher restarted";
  EXPECT_EQ(gaps.next(4), 0u);
  EXPECT_EQ(gaps.next(4 + SequenceGaps::kMaxGap + 2), 0u) << "too far ahead: another publisher";
  EXPECT_EQ(gaps.next(4 + SequenceGaps::kMaxGap + 4), 1u) << "counting goes on from the new number";
  EXPECT_EQ(gaps.next(0xFFFFFFFFu), 0u);
  EXPECT_EQ(gaps.next(1), 0u) << "wrapped around: a new count";
  EXPECT_EQ(gaps.next(3), 1u);
  EXPECT_EQ(gaps.next(3 + SequenceGaps::kMaxGap + 1), SequenceGaps::kMaxGap) << "the largest gap still counted";
}
