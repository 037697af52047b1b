#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>
#include <thread>
#include <tuple>

#include "stereo_fusion/map/BlockColumn.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/util/ThreadPool.h"

using namespace stereo_fusion;

namespace {
std::tuple<int, int, int> tup(const BlockKey& k) { return {k.x, k.y, k.z}; }
}  // namespace

TEST(BlockOctree, OctantIndexEq27To210HandWorked) {
  const BlockKey c{0, 0, 0};
  // I = 4·[x ≥ cx] + 2·[y ≥ cy] + [z ≥ cz]
  EXPECT_EQ(BlockOctree::octantIndex({-1, -1, -1}, c), 0);
  EXPECT_EQ(BlockOctree::octantIndex({-1, -1, 0}, c), 1);
  EXPECT_EQ(BlockOctree::octantIndex({-1, 0, -1}, c), 2);
  EXPECT_EQ(BlockOctree::octantIndex({0, -1, -1}, c), 4);
  EXPECT_EQ(BlockOctree::octantIndex({0, 0, 0}, c), 7);
  EXPECT_EQ(BlockOctree::octantIndex({5, -3, 2}, c), 5);
  EXPECT_EQ(BlockOctree::octantIndex({9, 9, 9}, {10, 8, 10}), 2);
}

TEST(BlockOctree, KeyForPointFloorsIncludingNegatives) {
  BlockOctree tree(0.16);
  EXPECT_EQ(tup(tree.keyForPoint({0.0, 0.159, 0.16})), std::make_tuple(0, 0, 1));
  EXPECT_EQ(tup(tree.keyForPoint({-0.01, -0.16, -0.17})), std::make_tuple(-1, -1, -2));
  EXPECT_NEAR((tree.blockOrigin({-1, 2, 0}) - Eigen::Vector3d(-0.16, 0.32, 0.0)).norm(), 0, 1e-12);
  EXPECT_FALSE(BlockOctree::keyInRange(tree.keyForPoint({NAN, 0, 0})));
  EXPECT_FALSE(BlockOctree::keyInRange(tree.keyForPoint({1e12, 0, 0})));
}

TEST(BlockOctree, RandomInsertAndFindAgainstStdMap) {
  BlockOctree tree(0.16);
  std::map<std::tuple<int, int, int>, VoxelBlock*> reference;
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> coord(-300, 300);
  for (int n = 0; n < 20000; ++n) {
    const BlockKey key{coord(rng), coord(rng), coord(rng)};
    bool allocated = false;
    VoxelBlock* block = tree.findOrAllocate(key, &allocated);
    ASSERT_NE(block, nullptr);
    EXPECT_EQ(block->key, key);
    auto it = reference.find(tup(key));
    EXPECT_EQ(allocated, it == reference.end());
    if (it == reference.end())
      reference[tup(key)] = block;
    else
      EXPECT_EQ(it->second, block);
  }
  EXPECT_EQ(tree.blockCount(), reference.size());
  for (const auto& [k, block] : reference)
    EXPECT_EQ(tree.find({std::get<0>(k), std::get<1>(k), std::get<2>(k)}), block);
  // Absent keys are not found and not created by find().
  int absent = 0;
  for (int n = 0; n < 5000; ++n) {
    const BlockKey key{coord(rng), coord(rng), coord(rng)};
    if (reference.count(tup(key))) continue;
    ++absent;
    EXPECT_EQ(tree.find(key), nullptr);
  }
  EXPECT_GT(absent, 4000);
  EXPECT_EQ(tree.blockCount(), reference.size());
}

TEST(BlockOctree, GrowsToPointsOneKilometreAwayInEveryDirection) {
  BlockOctree tree(0.16);
  const Eigen::Vector3d points[] = {{0.1, 0.1, 0.1},      {1000.0, 0, 0},  {-1000.0, 0, 0},
                                    {0, -1000.0, 500.0},  {0, 0, -1000.0}, {-700, -700, -700},
                                    {999.9, -999.9, 0.05}};
  std::vector<VoxelBlock*> blocks;
  for (const auto& p : points) {
    VoxelBlock* b = tree.findOrAllocate(tree.keyForPoint(p));
    ASSERT_NE(b, nullptr) << p.transpose();
    blocks.push_back(b);
  }
  for (size_t i = 0; i < blocks.size(); ++i)
    EXPECT_EQ(tree.find(tree.keyForPoint(points[i])), blocks[i]);
  EXPECT_EQ(tree.blockCount(), 7u);
  // 2000 m / 0.16 m = 12 500 blocks across: the root spans at least 2^14.
  EXPECT_GE(tree.height(), 14);
  EXPECT_LE(tree.height(), 16);
  // Search depth is the height: O(log N) in the extent, not O(N).
}

TEST(BlockOctree, RefusesKeysBeyondRange) {
  BlockOctree tree(0.16);
  EXPECT_EQ(tree.findOrAllocate({BlockOctree::kMaxKey + 1, 0, 0}), nullptr);
  EXPECT_EQ(tree.findOrAllocate({0, -BlockOctree::kMaxKey - 1, 0}), nullptr);
  EXPECT_NE(tree.findOrAllocate({BlockOctree::kMaxKey, -BlockOctree::kMaxKey, 0}), nullptr);
  EXPECT_EQ(tree.blockCount(), 1u);
}

TEST(BlockOctree, NeighbourQueriesFacesEdgesCorners) {
  BlockOctree tree(0.16);
  const BlockKey centre{-3, 7, 0};
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (dx || dy || dz) tree.findOrAllocate(centre.offset(dx, dy, dz));
  EXPECT_EQ(tree.find(centre), nullptr);
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        VoxelBlock* n = tree.neighbour(centre, dx, dy, dz);
        if (!dx && !dy && !dz) {
          EXPECT_EQ(n, nullptr);
        } else {
          ASSERT_NE(n, nullptr);
          EXPECT_EQ(n->key, centre.offset(dx, dy, dz));
        }
      }
  EXPECT_EQ(tree.neighbour(centre, 2, 0, 0), nullptr);
}

TEST(BlockOctree, MemoryAccounting) {
  BlockOctree tree(0.16);
  EXPECT_EQ(tree.memoryBytes(), 0u);
  // A 40 × 40 surface sheet of blocks, like a wall.
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) tree.findOrAllocate({x, y, 5});
  EXPECT_EQ(tree.blockCount(), 1600u);
  EXPECT_GE(tree.memoryBytes(), 1600 * sizeof(VoxelBlock));
  // Without voxels a block and its share of the octree stay under 400 B.
  EXPECT_LT(tree.bytesPerBlock(), 400.0);
  const size_t empty_bytes = tree.memoryBytes();
  // Levels by hand: all 1 600 hold 2³, 100 also 4³, 10 all three.
  size_t n = 0;
  for (VoxelBlock* b : tree.blocksSortedByKey()) {
    b->writableLevel(2);
    if (n < 100) b->writableLevel(1);
    if (n < 10) b->writableLevel(0);
    ++n;
  }
  const BlockOctree::MemoryUse use = tree.memoryUse();
  EXPECT_EQ(use.level_blocks[2], 1600u);
  EXPECT_EQ(use.level_blocks[1], 100u);
  EXPECT_EQ(use.level_blocks[0], 10u);
  EXPECT_EQ(use.level_bytes[2], 1600u * 8 * 12);
  EXPECT_EQ(use.level_bytes[1], 100u * 64 * 12);
  EXPECT_EQ(use.level_bytes[0], 10u * 512 * 12);
  EXPECT_EQ(use.block_bytes, 1600u * sizeof(VoxelBlock));
  EXPECT_EQ(tree.memoryBytes(), empty_bytes + (1600u * 8 + 100u * 64 + 10u * 512) * 12);
  // Without the levels: no walk, the structure only.
  EXPECT_EQ(tree.memoryUse(false).total(), empty_bytes);
  // Even all three levels everywhere stay inside the old 10 KiB budget.
  EXPECT_LT(static_cast<double>(sizeof(VoxelBlock) + 584 * 12), 10 * 1024.0);
  std::printf(
      "[ memory ] %zu blocks, %zu nodes: %.0f bytes per block incl. octree (block alone %zu)\n",
      tree.blockCount(), tree.nodeCount(), tree.bytesPerBlock(), sizeof(VoxelBlock));
  EXPECT_GT(tree.nodeCount(), 0u);
  EXPECT_LT(tree.nodeCount(), tree.blockCount());
  tree.clear();
  EXPECT_EQ(tree.blockCount(), 0u);
  EXPECT_EQ(tree.find({0, 0, 5}), nullptr);
  EXPECT_NE(tree.findOrAllocate({0, 0, 5}), nullptr);  // usable after clear
}

TEST(BlockOctree, SortedIterationIsDeterministic) {
  BlockOctree tree(0.16);
  tree.findOrAllocate({2, 0, 0});
  tree.findOrAllocate({0, 0, 1});
  tree.findOrAllocate({-1, 5, 0});
  const auto sorted = tree.blocksSortedByKey();
  ASSERT_EQ(sorted.size(), 3u);
  EXPECT_EQ(sorted[0]->key, (BlockKey{2, 0, 0}));   // z = 0, y = 0
  EXPECT_EQ(sorted[1]->key, (BlockKey{-1, 5, 0}));  // z = 0, y = 5
  EXPECT_EQ(sorted[2]->key, (BlockKey{0, 0, 1}));
}

TEST(BlockOctree, ConcurrentAllocationCreatesEachBlockOnce) {
  BlockOctree tree(0.16);
  std::vector<BlockKey> keys;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(-2000, 2000);  // forces root growth while racing
  for (int n = 0; n < 4000; ++n) keys.push_back({coord(rng), coord(rng) / 10, coord(rng) / 100});
  std::set<std::tuple<int, int, int>> unique;
  for (const auto& k : keys) unique.insert(tup(k));

  std::vector<std::vector<VoxelBlock*>> seen(4, std::vector<VoxelBlock*>(keys.size()));
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      // Every thread walks all keys, in a different order, and also reads concurrently.
      for (size_t n = 0; n < keys.size(); ++n) {
        const size_t i = (t % 2 == 0) ? n : keys.size() - 1 - n;
        seen[t][i] = tree.findOrAllocate(keys[i]);
        (void)tree.find(keys[(i * 7919) % keys.size()]);
      }
    });
  for (auto& th : threads) th.join();
  EXPECT_EQ(tree.blockCount(), unique.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    ASSERT_NE(seen[0][i], nullptr);
    for (int t = 1; t < 4; ++t) EXPECT_EQ(seen[t][i], seen[0][i]);
    EXPECT_EQ(tree.find(keys[i]), seen[0][i]);
  }
}

TEST(BlockOctree, SearchCounter) {
  BlockOctree tree(0.16);
  tree.resetSearchCount();
  tree.findOrAllocate({1, 2, 3});
  tree.find({1, 2, 3});
  tree.find({9, 9, 9});
  EXPECT_EQ(tree.searchCount(), 3u);
}

TEST(BlockOctree, ExtremeKeysOnEveryAxisStayBalancedAndExact) {
  // Keys at ±kMaxKey on all axes, in an order that once pushed the root past int32.
  BlockOctree tree(0.16);
  const int32_t K = BlockOctree::kMaxKey;
  const std::vector<BlockKey> keys = {{0, 0, 0}, {0, 0, K},    {0, 0, -K}, {0, -K, 0},  {-K, 0, 0},
                                      {K, K, K}, {-K, -K, -K}, {K, -K, K}, {-K, K, -K}, {1, -1, 1}};
  std::vector<VoxelBlock*> blocks;
  for (const BlockKey& k : keys) {
    blocks.push_back(tree.findOrAllocate(k));
    ASSERT_NE(blocks.back(), nullptr) << k;
  }
  for (size_t i = 0; i < keys.size(); ++i) EXPECT_EQ(tree.find(keys[i]), blocks[i]) << keys[i];
  EXPECT_EQ(tree.blockCount(), keys.size());
  EXPECT_LE(tree.height(), 31);
  EXPECT_EQ(tree.find({K, K, K - 1}), nullptr);
}

TEST(BlockOctree, BatchFindOrAllocateEqualsOneAtATime) {
  // Three batches into a growing tree: sorted neighbourhoods (the lookup's case, where each
  // search resumes from the previous key's path), then unsorted keys that force the root to
  // grow mid-batch, with repeats and out-of-range keys. Each must give what findOrAllocate()
  // gives key by key on a twin tree: the same blocks, the same "allocated" flags, the same
  // search count.
  std::mt19937 rng(11);
  std::vector<std::vector<BlockKey>> batches(3);
  for (int z = -3; z <= 3; ++z)
    for (int y = 5; y <= 9; ++y)
      for (int x = -40; x <= 40; x += 3) batches[0].push_back({x, y, z});
  std::uniform_int_distribution<int> near(-20, 20), far(-5000, 5000);
  for (int n = 0; n < 500; ++n) batches[1].push_back({near(rng), near(rng), near(rng)});
  std::sort(batches[1].begin(), batches[1].end());
  for (int n = 0; n < 500; ++n) batches[2].push_back({far(rng), near(rng), far(rng) / 10});
  batches[2].insert(batches[2].end(), batches[1].begin(), batches[1].begin() + 50);  // found now
  batches[2].push_back({BlockOctree::kMaxKey + 1, 0, 0});
  batches[2].push_back({0, -BlockOctree::kMaxKey - 1, 0});

  BlockOctree batched(0.16), single(0.16);
  for (const std::vector<BlockKey>& keys : batches) {
    batched.resetSearchCount();
    single.resetSearchCount();
    std::vector<VoxelBlock*> blocks(keys.size());
    std::vector<uint8_t> allocated(keys.size(), 7);
    batched.findOrAllocateBatch(keys.data(), keys.size(), blocks.data(), allocated.data());
    const uint64_t batch_searches = batched.searchCount();
    for (size_t i = 0; i < keys.size(); ++i) {
      bool single_allocated = true;
      const VoxelBlock* single_block = single.findOrAllocate(keys[i], &single_allocated);
      ASSERT_EQ(blocks[i] == nullptr, single_block == nullptr) << keys[i];
      EXPECT_EQ(allocated[i], single_allocated ? 1 : 0) << keys[i];
      if (blocks[i] != nullptr) {
        EXPECT_EQ(blocks[i]->key, keys[i]);
        EXPECT_EQ(batched.find(keys[i]), blocks[i]);
      }
    }
    EXPECT_EQ(batch_searches, single.searchCount());  // one per key in range
    EXPECT_EQ(batched.blockCount(), single.blockCount());
    EXPECT_EQ(batched.height(), single.height());
  }
}

// Stage columns (BlockColumn) are indexed by the block's row: dense, unique among live blocks,
// reused after an erase, and reset by clear().
TEST(BlockOctree, RowsAreDenseUniqueAndReusedAfterErase) {
  BlockOctree map(0.16);
  for (int x = 0; x < 10; ++x) map.findOrAllocate({x, 0, 0});
  EXPECT_EQ(map.rowCount(), 10u);
  std::set<uint32_t> rows;
  for (const VoxelBlock* b : map.blocks()) rows.insert(b->row);
  EXPECT_EQ(rows, (std::set<uint32_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  const uint32_t freed = map.find({3, 0, 0})->row;
  ASSERT_EQ(map.erase({{3, 0, 0}}), 1u);
  auto block = std::make_unique<VoxelBlock>();
  block->key = {0, 5, 0};
  const VoxelBlock* inserted = map.insert(std::move(block));
  ASSERT_NE(inserted, nullptr);
  EXPECT_EQ(inserted->row, freed);
  EXPECT_EQ(map.rowCount(), 10u);
  BlockColumn<int> column;
  column.fit(map);
  EXPECT_EQ(column.size(), 10u);
  column[*inserted] = 7;
  EXPECT_EQ(column[*map.find({0, 5, 0})], 7);
  // insert() refuses a taken key and an out-of-range one.
  auto twin = std::make_unique<VoxelBlock>();
  twin->key = {0, 5, 0};
  EXPECT_EQ(map.insert(std::move(twin)), nullptr);
  auto far = std::make_unique<VoxelBlock>();
  far->key = {BlockOctree::kMaxKey + 1, 0, 0};
  EXPECT_EQ(map.insert(std::move(far)), nullptr);
  map.clear();
  EXPECT_EQ(map.rowCount(), 0u);
  EXPECT_EQ(map.findOrAllocate({1, 1, 1})->row, 0u);
}

// collectBlocks() with a pool walks subtrees in parallel and must give exactly the serial walk:
// the same blocks in the same order, and exactly those a brute-force test of every block keeps.
TEST(BlockOctree, CollectBlocksInParallelEqualsTheSerialWalk) {
  BlockOctree tree(0.16);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(-200, 200);
  for (int n = 0; n < 30000; ++n) tree.findOrAllocate({coord(rng), coord(rng), coord(rng)});
  // A ball of 12 m around (3, -2, 1): a conservative test for nodes (the boxes' distance).
  const Eigen::Vector3d centre(3.0, -2.0, 1.0);
  const auto in_ball = [&](const Eigen::AlignedBox3d& box) {
    return box.squaredExteriorDistance(centre) <= 12.0 * 12.0;
  };
  std::vector<VoxelBlock*> serial, parallel;
  tree.collectBlocks(in_ball, &serial);
  ThreadPool pool(3);
  tree.collectBlocks(in_ball, &parallel, &pool);
  EXPECT_EQ(parallel, serial);
  size_t expected = 0;
  for (const VoxelBlock* b : tree.blocks()) {
    const Eigen::Vector3d lo = tree.blockOrigin(b->key);
    expected += in_ball(Eigen::AlignedBox3d(lo, lo + Eigen::Vector3d::Constant(0.16)));
  }
  EXPECT_EQ(serial.size(), expected);
  EXPECT_GT(expected, 500u);
  EXPECT_LT(expected, tree.blockCount());
}
