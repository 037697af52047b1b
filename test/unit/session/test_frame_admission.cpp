// FrameAdmission: tickets in arrival order, epochs that supersede earlier tickets, and every
// frame's outcome counted once.
#include <gtest/gtest.h>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/session/FrameAdmission.h"

using namespace stereo_fusion;

TEST(FrameAdmission, TicketsInArrivalOrderEpochsSupersedeAndOutcomesCountOnce) {
  FrameAdmission admission;
  const FrameTicket a = admission.arrive();
  const uint64_t clear = admission.clearTicket();
  const FrameTicket b = admission.arrive();
  EXPECT_LT(a.ticket, clear);
  EXPECT_LT(clear, b.ticket) << "frames and clears share one arrival order";
  EXPECT_TRUE(admission.isCurrent(a));
  admission.newEpoch();
  EXPECT_FALSE(admission.isCurrent(a)) << "a reset or load came after it";
  EXPECT_FALSE(admission.isCurrent(b));
  EXPECT_TRUE(admission.isCurrent(admission.arrive()));

  IntegrationResult r;
  r.accepted = true;
  r.rejected.speckle_pixels = 6;
  r.rejected.edge_pixels = 12;
  r.contradiction.pixels_rejected = 13;
  admission.countFused(r, false);
  r.reanchored = true;
  admission.countFused(r, true);
  admission.countDrop(RejectReason::kUnreadable);
  admission.countDrop(RejectReason::kUnreadable);
  admission.countDrop(RejectReason::kPoseJump);
  admission.countEvicted(3);
  EXPECT_EQ(admission.framesFused(), 2u);
  EXPECT_EQ(admission.framesRecleared(), 1u);
  EXPECT_EQ(admission.drops()[RejectReason::kUnreadable], 2u);
  EXPECT_EQ(admission.drops().total(), 3u);
  EXPECT_EQ(admission.blocksEvicted(), 3u);
  const FusedFrameTotals& totals = admission.fusedTotals();
  EXPECT_EQ(totals.speckle_pixels.load(), 12u);
  EXPECT_EQ(totals.edge_pixels.load(), 24u);
  EXPECT_EQ(totals.contradicting_pixels.load(), 26u);
  EXPECT_EQ(totals.reanchored.load(), 1u);
}
