#include <gtest/gtest.h>

#include <cmath>

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

void observe(VoxelBlock* block, int level, int i, int j, int k, float sdf_m, float weight = 1.0f) {
  Voxel& v = block->writableAt(level, i, j, k);
  v.sdf_m = sdf_m;
  v.weight = weight;
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
  tsdfCellStates(block.key, &block, {4, 0.02f, 1.0f}, &states);
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
  tsdfCellStates(block.key, &block, {8, 0.02f, 1.0f}, &states);
  ASSERT_EQ(states.size(), 1u);
  EXPECT_TRUE(states[0].cell == (CellIndex{-1, 2, 0}));
  EXPECT_TRUE(states[0].occupied);

  states.clear();
  tsdfCellStates(block.key, &block, {1, 0.02f, 1.0f}, &states);
  ASSERT_EQ(states.size(), 512u);
  size_t occupied = 0;
  for (const TsdfCellState& s : states) occupied += s.occupied;
  EXPECT_EQ(occupied, 64u);
  EXPECT_TRUE(stateOf(states, {-8 + 4, 16 + 4, 0}).occupied);
  EXPECT_FALSE(stateOf(states, {-8 + 3, 16 + 4, 0}).observed);

  states.clear();
  tsdfCellStates(block.key, nullptr, {4, 0.02f, 1.0f}, &states);
  ASSERT_EQ(states.size(), 8u);
  for (const TsdfCellState& s : states) EXPECT_FALSE(s.observed);
}

// Evidence and the centre's signed distance, hand-worked (2 cm voxels, cells 4 voxels wide). Cell
// (0, 0, 0) has its centre at finest (2, 2, 2), between voxels 1 and 2 on each axis. Voxels
// 1–2 hold a plane: sdf = 0.02·(x + 0.5) − 0.045 (surface at x = 2.25 voxels), −0.015 at x = 1
// and +0.005 at x = 2; the centre reads the mean, −0.005. With x = 2 below the minimum weight
// the cell has no surface and its centre reads the x = 1 voxels alone.
TEST(TsdfOccupancy, EvidenceNeedsTheMinimumWeightAndTheCentreIsInterpolated) {
  for (const float weight_x2 : {2.0f, 1.0f}) {
    VoxelBlock block;
    block.key = {0, 0, 0};
    for (int z = 1; z <= 2; ++z)
      for (int y = 1; y <= 2; ++y)
        for (int x = 1; x <= 2; ++x)
          observe(&block, 0, x, y, z, 0.02f * (x + 0.5f) - 0.045f, x == 2 ? weight_x2 : 2.0f);
    observe(&block, 2, 1, 1, 1, 0.05f, 5.0f);  // cell (1, 1, 1): one level-2 voxel, its centre
    observe(&block, 2, 1, 0, 0, 0.05f, 1.5f);  // cell (1, 0, 0): below the minimum: unobserved
    std::vector<TsdfCellState> states;
    tsdfCellStates(block.key, &block, {4, 0.02f, 2.0f}, &states);
    const TsdfCellState& cell = stateOf(states, {0, 0, 0});
    ASSERT_TRUE(cell.observed);
    if (weight_x2 >= 2.0f) {
      EXPECT_TRUE(cell.occupied);
      EXPECT_NEAR(cell.centre_sdf_m, -0.005f, 1e-6f);
    } else {
      EXPECT_FALSE(cell.occupied);
      EXPECT_NEAR(cell.centre_sdf_m, -0.015f, 1e-6f);
    }
    EXPECT_TRUE(stateOf(states, {1, 1, 1}).occupied);
    EXPECT_NEAR(stateOf(states, {1, 1, 1}).centre_sdf_m, 0.05f, 1e-6f);
    EXPECT_FALSE(stateOf(states, {1, 0, 0}).observed);
    EXPECT_TRUE(std::isnan(stateOf(states, {1, 0, 0}).centre_sdf_m));
  }
}

// A surface seen at 60° from its normal stores projective distances, twice the Euclidean ones:
// sdf = 0.04·(x + 0.5) − 0.09 over voxels 1–2: −0.03 at x = 1, +0.01 at x = 2, a slope of 2
// (0.04 m per 2 cm voxel). The centre interpolates to −0.01 and, all 8 corners evidence, reads
// −0.01 / 2 = −0.005. With a corner missing there is no gradient to trust: not divided.
TEST(TsdfOccupancy, TheCentreDistanceIsMadeEuclideanByTheGradient) {
  VoxelBlock block;
  block.key = {0, 0, 0};
  for (int z = 1; z <= 2; ++z)
    for (int y = 1; y <= 2; ++y)
      for (int x = 1; x <= 2; ++x) observe(&block, 0, x, y, z, 0.04f * (x + 0.5f) - 0.09f, 2.0f);
  std::vector<TsdfCellState> states;
  tsdfCellStates(block.key, &block, {4, 0.02f, 2.0f}, &states);
  EXPECT_NEAR(stateOf(states, {0, 0, 0}).centre_sdf_m, -0.005f, 1e-6f);
  // Without voxel (1, 1, 1) (−0.03): the 7 corners at weight 1/8 each renormalise to
  // (3·(−0.03) + 4·(+0.01)) / 7 = −0.05 / 7, not divided.
  block.writableAt(0, 1, 1, 1).weight = 1.0f;
  states.clear();
  tsdfCellStates(block.key, &block, {4, 0.02f, 2.0f}, &states);
  EXPECT_NEAR(stateOf(states, {0, 0, 0}).centre_sdf_m, -0.05f / 7.0f, 1e-6f);
}

}  // namespace
}  // namespace stereo_fusion
