// The change log that carries what fusion and eviction changed to the stages after them, and
// what the mesher changed to the texture pass and publishers: hand-worked event sequences.
#include <gtest/gtest.h>

#include "stereo_fusion/map/BlockChangeLog.h"

using namespace stereo_fusion;

namespace {
const BlockKey kA{0, 0, 0}, kB{1, 0, 0}, kC{0, 1, 0}, kD{-1, 0, 2};
}  // namespace

TEST(BlockChangeLog, EachConsumerTakesWhatChangedSinceItLastTookSortedAndOnce) {
  BlockChangeLog log;
  const BlockChangeLog::Consumer mesher = log.subscribe("mesher");
  log.recordUpdated({kD, kA});
  const BlockChangeLog::Consumer late = log.subscribe("late");  // sees only what comes after
  log.recordUpdated({kA, kB});
  EXPECT_EQ(log.pending(mesher), 4u);
  EXPECT_EQ(log.pending(late), 2u);
  EXPECT_EQ(log.name(late), "late");

  const BlockChangeLog::Changes first = log.take(mesher);
  // Key order (z, y, x): kA (0,0,0) < kB (1,0,0) < kD (-1,0,2); kA once.
  EXPECT_EQ(first.updated, (std::vector<BlockKey>{kA, kB, kD}));
  EXPECT_TRUE(first.erased.empty());
  EXPECT_EQ(log.pending(mesher), 0u);
  EXPECT_TRUE(log.take(mesher).empty());  // nothing new since

  // The late consumer still has its own two.
  EXPECT_EQ(log.take(late).updated, (std::vector<BlockKey>{kA, kB}));
}

TEST(BlockChangeLog, ABlockIsReportedAsItEnded) {
  BlockChangeLog log;
  const BlockChangeLog::Consumer c = log.subscribe("c");
  log.recordUpdated({kA, kB, kC});
  log.recordErased({kA, kB});  // updated, then erased: erased
  log.recordUpdated({kB});     // erased, then created again: updated
  log.recordErased({kD});      // erased only
  const BlockChangeLog::Changes changes = log.take(c);
  EXPECT_EQ(changes.updated, (std::vector<BlockKey>{kB, kC}));
  EXPECT_EQ(changes.erased, (std::vector<BlockKey>{kA, kD}));
}

TEST(BlockChangeLog, ClearForgetsPendingChangesButKeepsConsumers) {
  BlockChangeLog log;
  const BlockChangeLog::Consumer a = log.subscribe("a"), b = log.subscribe("b");
  log.recordUpdated({kA});
  log.clear();
  EXPECT_TRUE(log.take(a).empty());
  log.recordErased({kC});
  EXPECT_EQ(log.take(b).erased, (std::vector<BlockKey>{kC}));
  EXPECT_EQ(log.take(a).erased, (std::vector<BlockKey>{kC}));
}

TEST(BlockChangeLog, PeekLeavesTheChangesAndRestoreGivesThemBackToOneConsumer) {
  BlockChangeLog log;
  const BlockChangeLog::Consumer a = log.subscribe("a"), b = log.subscribe("b");
  log.recordUpdated({kB, kA});
  log.recordErased({kB, kD});
  const BlockChangeLog::Changes peeked = log.peek(a);
  EXPECT_EQ(peeked.updated, (std::vector<BlockKey>{kA}));
  EXPECT_EQ(peeked.erased, (std::vector<BlockKey>{kB, kD}));
  EXPECT_EQ(log.pending(a), 4u);  // still there
  // A resumed map: the changes come back to `a` alone, and take() reports them as before.
  BlockChangeLog resumed;
  const BlockChangeLog::Consumer ra = resumed.subscribe("a"), rb = resumed.subscribe("b");
  EXPECT_EQ(resumed.consumerCount(), 2u);
  resumed.restore(ra, peeked);
  const BlockChangeLog::Changes taken = resumed.take(ra);
  EXPECT_EQ(taken.updated, log.take(a).updated);
  EXPECT_EQ(taken.erased, peeked.erased);
  EXPECT_TRUE(resumed.take(rb).empty());
  EXPECT_EQ(log.take(b).erased, peeked.erased);
}
