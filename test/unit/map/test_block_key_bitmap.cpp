// BlockKeyBitmap: the lookup's de-duplication of a frame's blocks when their box is small.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "stereo_fusion/map/BlockKeyBitmap.h"

using namespace stereo_fusion;

TEST(BlockKeyBitmap, ReadsBackDistinctKeysInSortedOrder) {
  // A box across the origin and wider than a word in x (so rows span several words), keys
  // inserted in random order with repeats, including the box's corners.
  const BlockKey lo{-70, -5, -3}, hi{90, 6, 4};
  BlockKeyBitmap bitmap;
  ASSERT_TRUE(bitmap.reset(lo, hi));
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> x(lo.x, hi.x), y(lo.y, hi.y), z(lo.z, hi.z);
  std::set<BlockKey> reference;
  auto insert = [&](const BlockKey& key) {
    bitmap.insert(key);
    reference.insert(key);
  };
  insert(lo);
  insert(hi);
  for (int i = 0; i < 3000; ++i) insert({x(rng), y(rng), z(rng)});
  for (int i = 0; i < 500; ++i)
    insert(*std::next(reference.begin(), static_cast<long>(rng() % reference.size())));
  std::vector<BlockKey> keys = {{1, 2, 3}};  // appended to, not replaced
  bitmap.appendSorted(&keys);
  const std::vector<BlockKey> expected = [&] {
    std::vector<BlockKey> e = {{1, 2, 3}};
    e.insert(e.end(), reference.begin(), reference.end());
    return e;
  }();
  EXPECT_EQ(keys, expected);
}

TEST(BlockKeyBitmap, ResetEmptiesTheSet) {
  BlockKeyBitmap bitmap;
  ASSERT_TRUE(bitmap.reset({0, 0, 0}, {3, 3, 3}));
  bitmap.insert({1, 2, 3});
  ASSERT_TRUE(bitmap.reset({0, 0, 0}, {3, 3, 3}));
  bitmap.insert({3, 0, 0});
  std::vector<BlockKey> keys;
  bitmap.appendSorted(&keys);
  EXPECT_EQ(keys, (std::vector<BlockKey>{{3, 0, 0}}));
  // A single-block box.
  ASSERT_TRUE(bitmap.reset({-9, 4, 2}, {-9, 4, 2}));
  bitmap.insert({-9, 4, 2});
  keys.clear();
  bitmap.appendSorted(&keys);
  EXPECT_EQ(keys, (std::vector<BlockKey>{{-9, 4, 2}}));
}

TEST(BlockKeyBitmap, RefusesBoxesBeyondItsCap) {
  BlockKeyBitmap bitmap;
  // Rows round up to 64 bits: 1 × 512 × 512 blocks take 2^24 bits, one more row is too many.
  EXPECT_TRUE(bitmap.reset({0, 0, 0}, {0, 511, 511}));
  EXPECT_FALSE(bitmap.reset({0, 0, 0}, {0, 512, 511}));
  EXPECT_FALSE(bitmap.reset({-(1 << 28), -(1 << 28), -(1 << 28)}, {1 << 28, 1 << 28, 1 << 28}));
  EXPECT_FALSE(bitmap.reset({0, 0, 1}, {0, 0, 0}));  // empty box
}
