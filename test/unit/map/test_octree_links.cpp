// The neighbour links BlockOctree keeps in every block: they must equal a search for every
// offset in {-1,0,1}³ after any sequence of allocation (from several threads), erase, clear and
// swap, and erase must leave no link to a freed block.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <random>
#include <set>

#include "QuickMode.h"
#include "TestSupport.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/util/ThreadPool.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

/// Links a block holds to other blocks (the block itself not counted).
int linkCount(const VoxelBlock& block) {
  int n = 0;
  for (int slot = 0; slot < NeighbourLinks::kCount; ++slot)
    n += block.neighbours.at(slot) != nullptr;
  return n;
}

int totalLinks(const BlockOctree& map) {
  int n = 0;
  for (const VoxelBlock* b : map.blocks()) n += linkCount(*b);
  return n;
}

/// Allocates the 3×3×3 cube of blocks around `centre`.
void allocateCube(BlockOctree* map, const BlockKey& centre) {
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        ASSERT_NE(map->findOrAllocate(centre.offset(dx, dy, dz)), nullptr);
}

}  // namespace

TEST(BlockOctreeLinks, FullCubeHandWorked) {
  // In a full 3×3×3 cube a corner block touches 7 others, an edge block 11, a face centre 17
  // and the centre 26: 8·7 + 12·11 + 6·17 + 26 = 316 links, each pair linked both ways.
  BlockOctree map(0.16);
  const BlockKey centre{-1, 0, 5};  // straddles the x = 0 split of the root
  allocateCube(&map, centre);
  ASSERT_EQ(map.blockCount(), 27u);
  EXPECT_EQ(linkCount(*map.find(centre)), 26);
  EXPECT_EQ(linkCount(*map.find(centre.offset(-1, -1, -1))), 7);
  EXPECT_EQ(linkCount(*map.find(centre.offset(1, 1, 0))), 11);
  EXPECT_EQ(linkCount(*map.find(centre.offset(0, 0, 1))), 17);
  EXPECT_EQ(totalLinks(map), 316);
  const VoxelBlock& c = *map.find(centre);
  EXPECT_EQ(map.neighbour(c, 0, 0, 0), &c);
  EXPECT_EQ(map.neighbour(c, 1, -1, 0)->key, centre.offset(1, -1, 0));
  EXPECT_EQ(map.neighbour(*map.neighbour(c, 1, -1, 0), -1, 1, 0), &c);
  const LinkCheck check = checkNeighbourLinks(map);
  EXPECT_EQ(check.checked, 27u * 27u);
  EXPECT_EQ(check.linked, 316u + 27u);
  EXPECT_EQ(check.mismatched, 0u);
}

TEST(BlockOctreeLinks, EraseLeavesNoDanglingLink) {
  BlockOctree map(0.16);
  const BlockKey centre{3, -2, 0};
  allocateCube(&map, centre);
  map.findOrAllocate(centre.offset(2, 0, 0));  // outside the cube, touching its 9 blocks at x + 1
  ASSERT_EQ(totalLinks(map), 316 + 2 * 9);
  // The centre, and a corner with a doomed neighbour of its own (both unlinked before freeing).
  const std::vector<BlockKey> doomed_keys = {centre, centre.offset(1, 1, 1), centre.offset(1, 1, 0),
                                             centre.offset(7, 7, 7)};  // absent: ignored
  std::set<uintptr_t> doomed_addresses;
  for (const BlockKey& k : doomed_keys)
    if (const VoxelBlock* b = map.find(k)) doomed_addresses.insert(reinterpret_cast<uintptr_t>(b));
  ASSERT_EQ(doomed_addresses.size(), 3u);
  EXPECT_EQ(map.erase(doomed_keys), 3u);
  EXPECT_EQ(map.blockCount(), 25u);
  // The doomed touch 26 (centre), 11 + 1 (edge, with the outside block) and 7 + 1 (corner)
  // blocks; 3 of those pairs are among themselves, so 46 − 3 = 43 pairs vanish, two links each.
  EXPECT_EQ(totalLinks(map), 316 + 18 - 2 * 43);
  for (const VoxelBlock* b : map.blocks())
    for (int slot = 0; slot < NeighbourLinks::kCount; ++slot) {
      const VoxelBlock* n = b->neighbours.at(slot);
      if (n == nullptr) continue;
      EXPECT_EQ(doomed_addresses.count(reinterpret_cast<uintptr_t>(n)), 0u)
          << b->key << " slot " << slot;
      // Reading through every link: AddressSanitizer reports a link to a freed block here.
      EXPECT_NE(map.find(n->key), nullptr);
    }
  EXPECT_EQ(checkNeighbourLinks(map).mismatched, 0u);
  // Re-allocating an erased key links it again, both ways.
  VoxelBlock* back = map.findOrAllocate(centre);
  EXPECT_EQ(linkCount(*back), 24);  // 26 less the two still-erased
  EXPECT_EQ(map.neighbour(*map.find(centre.offset(-1, 0, 0)), 1, 0, 0), back);
  EXPECT_EQ(checkNeighbourLinks(map).mismatched, 0u);
}

TEST(BlockOctreeLinks, ReadingLinksIsNoSearchAndLinkingIsNotCounted) {
  BlockOctree map(0.16);
  allocateCube(&map, {0, 0, 0});
  map.resetSearchCount();
  map.findOrAllocate({2, 0, 0});  // links to 9 blocks, with searches of its own
  EXPECT_EQ(map.searchCount(), 1u);
  const VoxelBlock& c = *map.find({0, 0, 0});
  for (int d = 0; d < 27; ++d) (void)map.neighbour(c, d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1);
  EXPECT_EQ(map.searchCount(), 2u);
}

TEST(BlockOctreeLinks, ACopiedBlockIsUnlinkedAndAssignmentKeepsTheTargetsLinks) {
  BlockOctree map(0.16);
  allocateCube(&map, {0, 0, 0});
  VoxelBlock* centre = map.find({0, 0, 0});
  centre->writableVoxel(7).weight = 2.0f;
  const VoxelBlock copy = *centre;
  EXPECT_EQ(copy.voxel(7).weight, 2.0f);
  EXPECT_EQ(linkCount(copy), 0);
  VoxelBlock* corner = map.find({1, 1, 1});
  const BlockKey corner_key = corner->key;
  *corner = copy;  // restoring contents: the corner stays where it is in the octree
  corner->key = corner_key;
  EXPECT_EQ(corner->voxel(7).weight, 2.0f);
  EXPECT_EQ(linkCount(*corner), 7);
  EXPECT_EQ(checkNeighbourLinks(map).mismatched, 0u);
}

TEST(BlockOctreeLinks, EqualSearchesAfterRandomAllocateEraseClearSwap) {
  // Random operations on two octrees; allocation runs on two threads at once through the pool,
  // with lock-free finds in between. Keys cluster densely (most links non-null) around a centre
  // that sometimes jumps far away, so that the root grows under existing blocks.
  std::mt19937 rng(20261122);
  ThreadPool pool(2);
  BlockOctree trees[2] = {BlockOctree(0.16), BlockOctree(0.16)};
  BlockKey centre{0, 0, 0};
  std::uniform_int_distribution<int> near(-4, 4), far(-3000, 3000);
  const int steps = quickMode() ? 80 : 300;
  int allocations = 0, erases = 0, clears = 0, swaps = 0, root_growths = 0;
  size_t checked = 0, linked = 0, erased = 0;
  for (int step = 0; step < steps; ++step) {
    BlockOctree& tree = trees[rng() % 4 == 0 ? 1 : 0];
    const unsigned op = rng() % 20;
    if (op < 12) {
      if (rng() % 8 == 0) centre = {far(rng), far(rng), far(rng) / 10};
      std::vector<BlockKey> keys(96);
      for (BlockKey& k : keys) k = centre.offset(near(rng), near(rng), near(rng));
      const int height_before = tree.height();
      pool.parallelFor(keys.size(), 8, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
          ASSERT_NE(tree.findOrAllocate(keys[i]), nullptr);
          (void)tree.find(keys[(i * 37) % keys.size()]);
        }
      });
      root_growths += tree.height() > height_before && height_before > 0;
      ++allocations;
    } else if (op < 17) {
      std::vector<BlockKey> doomed;
      for (const VoxelBlock* b :
           tree.blocksSortedByKey())  // not allocation order: threads set that
        if (rng() % 3 == 0) doomed.push_back(b->key);
      if (!doomed.empty()) doomed.push_back(doomed.front());  // duplicates are ignored
      doomed.push_back(centre.offset(40, 0, 0));              // and so are absent keys
      erased += tree.erase(doomed);
      ++erases;
    } else if (op < 18) {
      tree.clear();
      ++clears;
    } else {
      trees[0].swap(trees[1]);
      ++swaps;
    }
    for (const BlockOctree& t : trees) {
      const LinkCheck c = checkNeighbourLinks(t);
      ASSERT_EQ(c.mismatched, 0u) << "step " << step << ", operation " << op;
      EXPECT_EQ(c.checked, 27 * t.blockCount());
      checked += c.checked;
      linked += c.linked;
    }
  }
  std::printf(
      "[ links ] %d allocation batches (%d grew the root), %d erases (%zu blocks), %d clears, %d "
      "swaps: "
      "%zu links checked, %zu non-null\n",
      allocations, root_growths, erases, erased, clears, swaps, checked, linked);
  EXPECT_GT(allocations, steps / 3);
  EXPECT_GT(root_growths, 0);
  EXPECT_GT(erased, 100u);
  EXPECT_GT(clears, 0);
  EXPECT_GT(swaps, 0);
  // Not vacuous: a good share of the compared pairs are real links, not nullptr == nullptr.
  EXPECT_GT(linked, checked / 8);
}
