// BlockKeySet: the de-duplication behind the lookup's frame blocks and the mesh store's owners.
#include <gtest/gtest.h>

#include <set>

#include "stereo_fusion/map/BlockKeySet.h"

using namespace stereo_fusion;

TEST(BlockKeySet, InsertReportsFirstSightingsOnly) {
  BlockKeySet set;
  set.reset(4);
  EXPECT_TRUE(set.insert({0, 0, 0}));
  EXPECT_TRUE(set.insert({1, 0, 0}));
  EXPECT_FALSE(set.insert({0, 0, 0}));
  EXPECT_TRUE(set.insert({-1, 0, 0}));
  EXPECT_FALSE(set.insert({1, 0, 0}));
  EXPECT_TRUE(set.insert({0, 0, -7}));
}

TEST(BlockKeySet, ResetForgetsAndGrowsWithTheNextPass) {
  BlockKeySet set;
  set.reset(2);
  EXPECT_TRUE(set.insert({5, 5, 5}));
  set.reset(2);
  EXPECT_TRUE(set.insert({5, 5, 5}));  // a new pass: seen again for the first time
  // A larger pass than the table was sized for: every key of a dense cube, each twice.
  set.reset(4096);
  std::set<BlockKey> reference;
  for (int round = 0; round < 2; ++round)
    for (int z = -8; z < 8; ++z)
      for (int y = -8; y < 8; ++y)
        for (int x = -8; x < 8; ++x)
          EXPECT_EQ(set.insert({x, y, z}), reference.insert({x, y, z}).second);
  EXPECT_EQ(reference.size(), 4096u);
}

TEST(BlockKeySet, ManyPassesStayIndependent) {
  // Generations advance once per pass; 70 000 passes must never mistake an old slot for a live one.
  BlockKeySet set;
  for (int pass = 0; pass < 70000; ++pass) {
    set.reset(1);
    ASSERT_TRUE(set.insert({pass % 3, 0, 0})) << "pass " << pass;
    ASSERT_FALSE(set.insert({pass % 3, 0, 0})) << "pass " << pass;
  }
}
