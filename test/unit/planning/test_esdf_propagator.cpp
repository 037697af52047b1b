#include <gtest/gtest.h>

#include <random>

#include "EsdfTestSupport.h"

namespace stereo_fusion {
namespace {

using test::maxErrorCells;
using test::storedDist2;

void addBlocks(PlanningBlockMap* blocks, int nx, int ny, int nz) {
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) (*blocks)[BlockKey{x, y, z}] = std::make_unique<PlanningBlock>();
}

void setOccupied(PlanningBlockMap* blocks, const CellIndex& c, bool occupied) {
  PlanningBlock::set(&blocks->at(planningBlockOf(c))->occupied, cellInBlock(c), occupied);
}

std::vector<BlockKey> keysOf(const PlanningBlockMap& blocks) {
  std::vector<BlockKey> keys;
  for (const auto& [key, block] : blocks) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  return keys;
}

// One obstacle cell at (8, 8, 8) in a 2×2×2-block region: every cell within the max distance
// reads |offset|² exactly (hand-worked: (11, 8, 8) → 9, (9, 9, 9) → 3, (12, 11, 8) → 25; and
// (8, 8, 14) → 36 > 25 = max → no site); the obstacle itself reads 1 (its face neighbour is free).
TEST(EsdfPropagator, OneObstacleGivesExactSquaredDistances) {
  PlanningBlockMap blocks;
  addBlocks(&blocks, 2, 2, 2);
  const CellIndex obstacle{8, 8, 8};
  setOccupied(&blocks, obstacle, true);
  EsdfPropagator propagator;
  propagator.update(&blocks, {obstacle}, keysOf(blocks), 25);
  EXPECT_EQ(storedDist2(blocks, {11, 8, 8}), 9);
  EXPECT_EQ(storedDist2(blocks, {9, 9, 9}), 3);
  EXPECT_EQ(storedDist2(blocks, {12, 11, 8}), 25);
  EXPECT_EQ(storedDist2(blocks, {8, 8, 14}), PlanningBlock::kNoSite);
  EXPECT_EQ(storedDist2(blocks, obstacle), 1);
  EXPECT_EQ(maxErrorCells(blocks, 25), 0.0);
}

// Removing the obstacle again (a raise) leaves no site anywhere; adding a second one moves
// the midpoint's distance to the nearer.
TEST(EsdfPropagator, RemovingAnObstacleRaisesItsCells) {
  PlanningBlockMap blocks;
  addBlocks(&blocks, 2, 2, 2);
  EsdfPropagator propagator;
  setOccupied(&blocks, {4, 8, 8}, true);
  propagator.update(&blocks, {{4, 8, 8}}, keysOf(blocks), 64);
  setOccupied(&blocks, {12, 8, 8}, true);
  propagator.update(&blocks, {{12, 8, 8}}, {}, 64);
  EXPECT_EQ(storedDist2(blocks, {9, 8, 8}), 9);  // 3 from (12, 8, 8), 5 from (4, 8, 8)
  setOccupied(&blocks, {12, 8, 8}, false);
  propagator.update(&blocks, {{12, 8, 8}}, {}, 64);
  EXPECT_EQ(storedDist2(blocks, {9, 8, 8}), 25);
  setOccupied(&blocks, {4, 8, 8}, false);
  propagator.update(&blocks, {{4, 8, 8}}, {}, 64);
  for (const auto& [key, block] : blocks)
    for (int c = 0; c < PlanningBlock::kCells; ++c)
      EXPECT_EQ(block->dist2[c], PlanningBlock::kNoSite);
}

// Inside an obstacle the distance is to the nearest cell that is not occupied: a 5-cell-thick
// slab reads 1, 4, 9 from its faces inwards (hand-worked), negative in the signed field.
TEST(EsdfPropagator, InsideASlabCountsToItsFaces) {
  PlanningBlockMap blocks;
  addBlocks(&blocks, 2, 2, 2);
  std::vector<CellIndex> flipped;
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 6; x <= 10; ++x) {
        setOccupied(&blocks, {x, y, z}, true);
        flipped.push_back({x, y, z});
      }
  EsdfPropagator propagator;
  propagator.update(&blocks, flipped, keysOf(blocks), 100);
  EXPECT_EQ(storedDist2(blocks, {6, 8, 8}), 1);
  EXPECT_EQ(storedDist2(blocks, {7, 8, 8}), 4);
  EXPECT_EQ(storedDist2(blocks, {8, 8, 8}), 9);
  EXPECT_EQ(storedDist2(blocks, {10, 8, 8}), 1);
  EXPECT_EQ(storedDist2(blocks, {3, 8, 8}), 9);
  EXPECT_EQ(maxErrorCells(blocks, 100), 0.0);
}

// Random obstacles flipped on and off over many updates: the incremental field stays within
// half a cell of the brute force everywhere and equals a rebuild from scratch cell for cell.
TEST(EsdfPropagator, IncrementalMatchesBruteForceAndRebuildAfterRandomFlips) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    std::mt19937 rng(seed);
    PlanningBlockMap blocks;
    addBlocks(&blocks, 3, 3, 2);
    EsdfPropagator propagator;
    propagator.update(&blocks, {}, keysOf(blocks), 49);
    std::uniform_int_distribution<int> x(0, 23), y(0, 23), z(0, 15);
    std::vector<CellIndex> occupied;
    for (int round = 0; round < 12; ++round) {
      std::vector<CellIndex> flipped;
      // Grow: a few short walls; shrink: drop some earlier cells.
      for (int w = 0; w < 3; ++w) {
        const CellIndex start{x(rng), y(rng), z(rng)};
        for (int i = 0; i < 6; ++i) {
          const CellIndex c{std::min(start.x + i, 23), start.y, start.z};
          if (cellOccupied(blocks, c)) continue;
          setOccupied(&blocks, c, true);
          flipped.push_back(c);
          occupied.push_back(c);
        }
      }
      std::shuffle(occupied.begin(), occupied.end(), rng);
      for (int i = 0; i < 5 && !occupied.empty(); ++i) {
        const CellIndex c = occupied.back();
        occupied.pop_back();
        if (!cellOccupied(blocks, c)) continue;
        setOccupied(&blocks, c, false);
        flipped.push_back(c);
      }
      propagator.update(&blocks, flipped, {}, 49);
      ASSERT_LE(maxErrorCells(blocks, 49), 0.5) << "seed " << seed << " round " << round;
    }
    PlanningBlockMap rebuilt;
    for (const auto& [key, block] : blocks) rebuilt[key] = std::make_unique<PlanningBlock>(*block);
    propagator.rebuild(&rebuilt, 49);
    size_t differing = 0;
    for (const auto& [key, block] : blocks)
      for (int c = 0; c < PlanningBlock::kCells; ++c)
        differing += block->dist2[c] != rebuilt.at(key)->dist2[c];
    EXPECT_EQ(differing, 0u) << "seed " << seed;
  }
}

}  // namespace
}  // namespace stereo_fusion
