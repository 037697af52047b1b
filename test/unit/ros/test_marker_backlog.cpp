#include <gtest/gtest.h>

#include "stereo_fusion/ros/MarkerBacklog.h"

using namespace stereo_fusion;

// Three flushes of mesh changes between two marker publishes: the backlog must say what rviz
// needs to end up with the same blocks as ~mesh_update's subscriber.
TEST(MarkerBacklog, MergesFlushesInOrderSoTheLastWordOnABlockWins) {
  MarkerBacklog backlog;
  EXPECT_TRUE(backlog.empty());
  const BlockKey a{0, 0, 0}, b{1, 0, 0}, c{0, 2, 0}, d{-1, 0, 5};
  backlog.add({a, b}, {c});  // c was drawn earlier and is gone now
  backlog.add({c, b}, {a});  // c back, a gone
  backlog.add({}, {d});
  EXPECT_FALSE(backlog.empty());
  std::vector<BlockKey> changed, removed;
  backlog.take(&changed, &removed);
  EXPECT_EQ(changed, (std::vector<BlockKey>{b, c}));  // sorted by key, once each
  EXPECT_EQ(removed, (std::vector<BlockKey>{a, d}));
  EXPECT_TRUE(backlog.empty());
  backlog.take(&changed, &removed);
  EXPECT_TRUE(changed.empty());
  EXPECT_TRUE(removed.empty());
}
