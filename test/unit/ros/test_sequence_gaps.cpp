#include <gtest/gtest.h>

#include "stereo_fusion/ros/SequenceGaps.h"

using namespace stereo_fusion;

TEST(SequenceGaps, CountsTheNumbersSkippedFromTheFirstMessageOn) {
  SequenceGaps gaps;
  EXPECT_EQ(gaps.next(0), 0u);  // roscpp numbers a publisher's messages from 0
  EXPECT_EQ(gaps.next(3), 2u) << "1 and 2 were lost right after the first";
  EXPECT_EQ(gaps.next(4), 0u);
  EXPECT_EQ(gaps.next(14), 9u);
  EXPECT_EQ(gaps.next(15 + SequenceGaps::kMaxGap), SequenceGaps::kMaxGap)
      << "the largest gap still counted";
}

TEST(SequenceGaps, RepeatsRestartsForeignNumbersAndUnnumberedBagsCountNothing) {
  SequenceGaps gaps;
  EXPECT_EQ(gaps.next(500), 0u) << "nothing before the first message is known";
  EXPECT_EQ(gaps.next(500), 0u) << "a repeated number is not a gap";
  EXPECT_EQ(gaps.next(0), 0u) << "the publisher restarted";
  EXPECT_EQ(gaps.next(2), 1u) << "counting goes on from the new number";
  EXPECT_EQ(gaps.next(2 + SequenceGaps::kMaxGap + 2), 0u) << "too far ahead: another publisher";
  EXPECT_EQ(gaps.next(2 + SequenceGaps::kMaxGap + 4), 1u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(SequenceGaps().next(0), 0u);
  SequenceGaps zeros;  // a bag recorded from a publisher that left every seq at 0
  for (int i = 0; i < 5; ++i) EXPECT_EQ(zeros.next(0), 0u);
}

TEST(SequenceGaps, TheWrapAroundIsNotAGap) {
  SequenceGaps gaps;
  EXPECT_EQ(gaps.next(0xFFFFFFFEu), 0u);
  EXPECT_EQ(gaps.next(0xFFFFFFFFu), 0u);
  EXPECT_EQ(gaps.next(0u), 0u);
  EXPECT_EQ(gaps.next(2u), 1u);
  SequenceGaps across;
  EXPECT_EQ(across.next(0xFFFFFFFEu), 0u);
  EXPECT_EQ(across.next(1u), 2u) << "0xFFFFFFFF and 0 were lost across the wrap";
}
