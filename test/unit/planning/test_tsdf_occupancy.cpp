#include <gtest/gtest.h>

#include "stereo_fusion/planning/TsdfOccupancy.h"

namespace stereo_fusion {
namespace {

const TsdfCellState& stateOf(const std::vector<TsdfCellState>& states, const CellIndex& cell) {
  for (const TsdfCellState& s : states)
    if (s.cell == cell) return s;
  static const TsdfCellState none;
  ADD_FAILURE() << "cell " << cell.x << " " << cell.y << " " << cell.z << " not reported";
  return none;
}

void observe(VoxelBlock* block, int level, int i, int j, int k, float sdf_m) {
  Voxel& v = block->writableAt(level, i, j, k);
  v.sdf_m = sdf_m;
  v.weight = 1.0f;
}

// Cells 4 voxels wide (2 cm voxels, 8 cm cells): TSDF block (1, 0, 0) covers cells x 2–3,
// y 0–1, z 0–1. Hand-worked: the finest level observed over a cell decides.
TEST(TsdfOccupancy, TheFinestObservedLevelOverACellDecides) {
  VoxelBlock block;
  block.key = {1, 0, 0};
  observe(&block, 0, 5, 1, 6, -0.01f);  // finest (5, 1, 6) → cell (1, 0, 1): in front
  observe(&block, 2, 1, 0, 1, +0.05f);  // level 2 (1, 0, 1) spans finest 4–7 → same cell: overruled
  observe(&block, 1, 1, 0, 0, +0.02f);  // level 1 (1, 0, 0) spans finest 2–3 → cell (0, 0, 0)
  observe(&block, 2, 0, 0, 0, -0.05f);  // level 2 over cell (0, 0, 0): level 1 is finer there
  observe(&block, 2, 1, 1, 1, +0.05f);  // alone over cell (1, 1, 1)
  std::vector<TsdfCellState> states;
  tsdfCellStates(block.key, &block, 4, &states);
  ASSERT_EQ(states.size(), 8u);
  EXPECT_TRUE(stateOf(states, {3, 0, 1}).observed);
  EXPECT_FALSE(stateOf(states, {3, 0, 1}).occupied);
  EXPECT_TRUE(stateOf(states, {2, 0, 0}).occupied);
  EXPECT_TRUE(stateOf(states, {3, 1, 1}).occupied);
  EXPECT_FALSE(stateOf(states, {2, 1, 0}).observed);  // nothing over it
  EXPECT_FALSE(stateOf(states, {2, 1, 0}).occupied);
}

// One cell per TSDF block (8 voxels wide), and cells one voxel wide under a 2³ voxel that
// spans 4³ of them; an erased block reports its cells unobserved.
TEST(TsdfOccupancy, CellsOfOneAndEightVoxelsAndErasedBlocks) {
  VoxelBlock block;
  block.key = {-1, 2, 0};
  observe(&block, 2, 1, 1, 0, 0.0f);  // sdf 0 is on the surface: occupied
  std::vector<TsdfCellState> states;
  tsdfCellStates(block.key, &block, 8, &states);
  ASSERT_EQ(states.size(), 1u);
  EXPECT_TRUE(states[0].cell == (CellIndex{-1, 2, 0}));
  EXPECT_TRUE(states[0].occupied);

  states.clear();
  tsdfCellStates(block.key, &block, 1, &states);
  ASSERT_EQ(states.size(), 512u);
  size_t occupied = 0;
  for (const TsdfCellState& s : states) occupied += s.occupied;
  EXPECT_EQ(occupied, 64u);
  EXPECT_TRUE(stateOf(states, {-8 + 4, 16 + 4, 0}).occupied);
  EXPECT_FALSE(stateOf(states, {-8 + 3, 16 + 4, 0}).observed);

  states.clear();
  tsdfCellStates(block.key, nullptr, 4, &states);
  ASSERT_EQ(states.size(), 8u);
  for (const TsdfCellState& s : states) EXPECT_FALSE(s.observed);
}

}  // namespace
}  // namespace stereo_fusion
