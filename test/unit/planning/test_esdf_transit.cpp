#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "stereo_fusion/planning/EsdfTransit.h"

namespace stereo_fusion {
namespace {

PlanningBlock* addBlock(PlanningBlockMap* blocks, const BlockKey& key) {
  auto& slot = (*blocks)[key];
  if (!slot) slot = std::make_unique<PlanningBlock>();
  return slot.get();
}

void setCell(PlanningBlockMap* blocks, const CellIndex& c, bool occupied) {
  PlanningBlock* block = addBlock(blocks, planningBlockOf(c));
  PlanningBlock::set(occupied ? &block->occupied : &block->seen_free, cellInBlock(c), true);
  if (occupied) PlanningBlock::set(&block->tsdf_observed, cellInBlock(c), true);
}

CellBox box(Eigen::Vector3i min, Eigen::Vector3i max) {
  CellBox b;
  b.min = min;
  b.max = max;
  return b;
}

/// Allocates every transit block the rule asks for, as PlanningMap does for blocks seen anew.
void applyRule(const EsdfTransit& transit, PlanningBlockMap* blocks) {
  std::vector<BlockKey> keys;
  for (const auto& [key, block] : *blocks) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  for (const BlockKey& key : keys)
    for (const BlockKey& t : transit.needed(*blocks, key, blockKinds(*blocks->at(key))))
      addBlock(blocks, t);
}

/// Largest |distance − brute force| in cells over the known cells that are not occupied (the
/// cells a query reads), against every occupied cell.
double maxFreeCellErrorCells(const PlanningBlockMap& blocks, uint32_t max_dist2) {
  std::vector<CellIndex> occupied, free_cells;
  for (const auto& [key, block] : blocks)
    for (int c = 0; c < PlanningBlock::kCells; ++c) {
      if (PlanningBlock::test(block->occupied, c))
        occupied.push_back(cellOf(key, c));
      else if (block->known(c))
        free_cells.push_back(cellOf(key, c));
    }
  const double max_cells = std::sqrt(double(max_dist2));
  double worst = 0.0;
  for (const CellIndex& f : free_cells) {
    uint32_t best = PlanningBlock::kNoSite;
    for (const CellIndex& o : occupied) {
      const int64_t dx = o.x - f.x, dy = o.y - f.y, dz = o.z - f.z;
      const int64_t d2 = dx * dx + dy * dy + dz * dz;
      if (d2 <= max_dist2 && d2 < best) best = static_cast<uint32_t>(d2);
    }
    const uint16_t stored = blocks.at(planningBlockOf(f))->dist2[cellInBlock(f)];
    auto cells = [&](uint32_t d2) {
      return d2 == PlanningBlock::kNoSite ? max_cells : std::sqrt(double(d2));
    };
    worst = std::max(worst, std::abs(cells(stored) - cells(best)));
  }
  return worst;
}

// Reach, hand-worked: blocks r apart hold cells 8r − 7 apart, so 25 cells reach 4 blocks
// ((8·4 − 7)² = 625) and 20 cells 3 ((8·3 − 7)² = 289 ≤ 400 < 25² = 625).
TEST(EsdfTransit, ReachInBlocksAndCells) {
  EXPECT_EQ(EsdfTransit(625).reachBlocks(), 4);
  EXPECT_EQ(EsdfTransit(400).reachBlocks(), 3);
  const EsdfTransit transit(625);
  const CellBox origin = box({0, 0, 0}, {1, 1, 1});
  EXPECT_TRUE(transit.withinReach(origin, box({25, 0, 0}, {26, 1, 1})));     // 25² = 625
  EXPECT_FALSE(transit.withinReach(origin, box({26, 0, 0}, {27, 1, 1})));    // 26² = 676
  EXPECT_TRUE(transit.withinReach(origin, box({15, 20, 0}, {16, 21, 1})));   // 225 + 400
  EXPECT_FALSE(transit.withinReach(origin, box({15, 21, 0}, {16, 22, 1})));  // 225 + 441
}

// The boxes around set bits, in cell coordinates: cells (1, 2, 3) and (5, 0, 7) of block
// (1, 0, −1) span x 9..13, y 0..2, z −5..−1.
TEST(EsdfTransit, BoxesAroundOccupiedAndFreeCells) {
  PlanningBlockMap blocks;
  const BlockKey key{1, 0, -1};
  setCell(&blocks, cellOf(key, PlanningBlock::index(1, 2, 3)), true);
  setCell(&blocks, cellOf(key, PlanningBlock::index(5, 0, 7)), true);
  setCell(&blocks, cellOf(key, PlanningBlock::index(0, 7, 0)), false);
  const PlanningBlock& block = *blocks.at(key);
  const CellBox occupied = occupiedBox(key, block);
  EXPECT_EQ(occupied.min, Eigen::Vector3i(9, 0, -5));
  EXPECT_EQ(occupied.max, Eigen::Vector3i(14, 3, 0));
  const CellBox free = freeBox(key, block);
  EXPECT_EQ(free.min, Eigen::Vector3i(8, 7, -8));
  EXPECT_EQ(free.max, Eigen::Vector3i(9, 8, -7));
  EXPECT_EQ(blockKinds(block), kHoldsOccupied | kHoldsFree);
  EXPECT_TRUE(occupiedBox({0, 0, 0}, PlanningBlock()).empty());
}

// The hull of a one-cell-thick rod from cell (0, 0, 0) to cell (16, 0, 0) overlaps block
// (1, 0, 0) and only touches (1, 1, 0); a diagonal rod from (0, 0, 0) to (16, 16, 0) clips
// the corner of block (1, 0, 0): at t ∈ (7/16, 1/2) it spans x (16t, 16t + 1) ∋ 8 with y < 8.
TEST(EsdfTransit, OverlapsHullHandWorked) {
  const CellBox a = box({0, 0, 0}, {1, 1, 1});
  const CellBox b = box({16, 0, 0}, {17, 1, 1});
  EXPECT_TRUE(EsdfTransit::overlapsHull(blockBox({1, 0, 0}), a, b));
  EXPECT_FALSE(EsdfTransit::overlapsHull(blockBox({1, 1, 0}), a, b));
  const CellBox touching = box({0, 7, 0}, {1, 8, 1}), touching_end = box({16, 7, 0}, {17, 8, 1});
  EXPECT_FALSE(EsdfTransit::overlapsHull(blockBox({1, 1, 0}), touching, touching_end));
  const CellBox diagonal_end = box({16, 16, 0}, {17, 17, 1});
  EXPECT_TRUE(EsdfTransit::overlapsHull(blockBox({1, 1, 0}), a, diagonal_end));
  EXPECT_TRUE(EsdfTransit::overlapsHull(blockBox({1, 0, 0}), a, diagonal_end));
  EXPECT_FALSE(EsdfTransit::overlapsHull(blockBox({2, 0, 0}), a, diagonal_end));
  EXPECT_FALSE(EsdfTransit::overlapsHull(blockBox({1, 1, 1}), a, diagonal_end));
  EXPECT_FALSE(EsdfTransit::overlapsHull(blockBox({-1, 0, 0}), a, b));
}

// A wall face (cells x = 0 of block (0, 0, 0)) and free space in block (2, 0, 0) with nothing
// known between: only block (1, 0, 0) is needed, and through it the free cells read their
// distance to the wall (cell (16, 4, 4): 16 cells; without it, no site reaches them).
TEST(EsdfTransit, AHoleBetweenAWallAndFreeSpaceIsBridged) {
  PlanningBlockMap blocks;
  for (int y = 0; y < 8; ++y)
    for (int z = 0; z < 8; ++z) setCell(&blocks, {0, y, z}, true);
  for (int x = 16; x < 24; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 8; ++z) setCell(&blocks, {x, y, z}, false);
  const uint32_t max_dist2 = 400;
  EsdfTransit transit(max_dist2);
  EsdfPropagator propagator;
  propagator.rebuild(&blocks, max_dist2);
  EXPECT_EQ(blocks.at({2, 0, 0})->dist2[cellInBlock({16, 4, 4})], PlanningBlock::kNoSite);
  const std::vector<BlockKey> between{{1, 0, 0}};
  EXPECT_EQ(transit.needed(blocks, {0, 0, 0}, kHoldsOccupied), between);
  EXPECT_EQ(transit.needed(blocks, {2, 0, 0}, kHoldsFree), between);
  EXPECT_TRUE(transit.needed(blocks, {0, 0, 0}, kHoldsFree).empty());  // no free cell there
  applyRule(transit, &blocks);
  EXPECT_EQ(blocks.size(), 3u);
  propagator.rebuild(&blocks, max_dist2);
  EXPECT_EQ(blocks.at({2, 0, 0})->dist2[cellInBlock({16, 4, 4})], 256);
  EXPECT_EQ(blocks.at({2, 0, 0})->dist2[cellInBlock({20, 4, 4})], 400);
  EXPECT_EQ(blocks.at({2, 0, 0})->dist2[cellInBlock({21, 4, 4})], PlanningBlock::kNoSite);
}

// Random walls and free space in blocks with holes between them: without the transit blocks
// some free cells read too far; with them every free cell is within half a cell of the brute
// force (the ESDF's contract), and the transit blocks hold no known cell.
TEST(EsdfTransit, RandomHolesKeepFreeCellsExact) {
  const uint32_t max_dist2 = 100;
  const EsdfTransit transit(max_dist2);
  EsdfPropagator propagator;
  int maps_with_errors = 0;
  for (uint32_t seed = 1; seed <= 8; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> cell(0, PlanningBlock::kSide - 1);
    std::bernoulli_distribution absent(0.45), has_wall(0.4);
    PlanningBlockMap blocks;
    for (int bz = 0; bz < 2; ++bz)
      for (int by = 0; by < 5; ++by)
        for (int bx = 0; bx < 5; ++bx) {
          if (absent(rng)) continue;
          const BlockKey key{bx, by, bz};
          PlanningBlock* block = addBlock(&blocks, key);
          // A patch of free cells, and sometimes a short wall.
          const int x0 = cell(rng), y0 = cell(rng), z0 = cell(rng);
          for (int z = z0; z < std::min(z0 + 4, 8); ++z)
            for (int y = y0; y < std::min(y0 + 4, 8); ++y)
              for (int x = x0; x < std::min(x0 + 4, 8); ++x)
                PlanningBlock::set(&block->seen_free, PlanningBlock::index(x, y, z), true);
          if (has_wall(rng)) {
            const int wx = cell(rng), wz = cell(rng);
            for (int y = 0; y < 8; ++y)
              setCell(&blocks, cellOf(key, PlanningBlock::index(wx, y, wz)), true);
          }
        }
    propagator.rebuild(&blocks, max_dist2);
    if (maxFreeCellErrorCells(blocks, max_dist2) > 0.5) ++maps_with_errors;
    const size_t known_blocks = blocks.size();
    applyRule(transit, &blocks);
    propagator.rebuild(&blocks, max_dist2);
    EXPECT_LE(maxFreeCellErrorCells(blocks, max_dist2), 0.5) << "seed " << seed;
    size_t transit_blocks = 0;
    for (const auto& [key, block] : blocks) transit_blocks += !block->anyKnown();
    EXPECT_EQ(transit_blocks, blocks.size() - known_blocks);
  }
  EXPECT_GE(maps_with_errors, 2);  // the holes matter: the test would catch a rule that did nothing
}

}  // namespace
}  // namespace stereo_fusion
