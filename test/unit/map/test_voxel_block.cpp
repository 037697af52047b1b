#include <gtest/gtest.h>

#include <cmath>

#include "stereo_fusion/map/VoxelBlock.h"

using namespace stereo_fusion;

TEST(VoxelBlock, SizesMatchTheMemoryTable) {
  static_assert(sizeof(Voxel) == 12);
  static_assert(VoxelBlock::kVoxelCount == 8 * 8 * 8 + 4 * 4 * 4 + 2 * 2 * 2);
  EXPECT_EQ(VoxelBlock::kVoxelCount, 584);
  EXPECT_EQ(NeighbourLinks::kCount, 26);
  // doc/maps.md, Memory: a fixed part of 248 B (key, row, three level pointers, 26 links), then
  // 96 / 768 / 6 144 B per allocated level (2³ / 4³ / 8³).
  EXPECT_EQ(sizeof(VoxelBlock), 248u);
  VoxelBlock block;
  EXPECT_EQ(block.voxelBytes(), 0u);
  block.writableLevel(2);
  EXPECT_EQ(block.voxelBytes(), 96u);
  block.writableLevel(1);
  EXPECT_EQ(block.voxelBytes(), 96u + 768u);
  block.writableLevel(0);
  EXPECT_EQ(block.voxelBytes(), 96u + 768u + 6144u);
}

TEST(VoxelBlock, FlatIndexEq34Eq35HandWorked) {
  // I_B(i,j,k) = i + j·B + k·B² + O
  EXPECT_EQ(VoxelBlock::index(0, 0, 0, 0), 0);
  EXPECT_EQ(VoxelBlock::index(0, 1, 2, 3), 1 + 2 * 8 + 3 * 64);  // 209
  EXPECT_EQ(VoxelBlock::index(0, 7, 7, 7), 511);
  EXPECT_EQ(VoxelBlock::index(1, 0, 0, 0), 512);
  EXPECT_EQ(VoxelBlock::index(1, 1, 2, 3), 1 + 2 * 4 + 3 * 16 + 512);  // 569
  EXPECT_EQ(VoxelBlock::index(2, 0, 0, 0), 576);
  EXPECT_EQ(VoxelBlock::index(2, 1, 1, 0), 1 + 2 + 576);  // 579
  EXPECT_EQ(VoxelBlock::index(2, 1, 1, 1), 583);
}

TEST(VoxelBlock, IndexIsABijectionOntoTheArray) {
  std::vector<int> hits(VoxelBlock::kVoxelCount, 0);
  for (int level = 0; level < kNumLevels; ++level) {
    const int side = levelSide(level);
    for (int k = 0; k < side; ++k)
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) ++hits[VoxelBlock::index(level, i, j, k)];
  }
  for (int h : hits) EXPECT_EQ(h, 1);
}

TEST(VoxelBlock, LevelSideAndScaleEq33) {
  EXPECT_EQ(levelSide(0), 8);
  EXPECT_EQ(levelSide(1), 4);
  EXPECT_EQ(levelSide(2), 2);
  for (int l = 0; l < kNumLevels; ++l) EXPECT_EQ(levelSide(l) * levelScale(l), 8);  // B = 8/s
}

TEST(VoxelBlock, LevelForDepthEq32HandWorked) {
  const LevelThresholds t;  // thesis values: s = 2 from 2 m, s = 4 from 4 m
  EXPECT_EQ(levelForDepth(0.5, t), 0);
  EXPECT_EQ(levelForDepth(1.0, t), 0);
  EXPECT_EQ(levelForDepth(1.99, t), 0);  // ⌊log2 1.99⌋ = 0 → s = 1
  EXPECT_EQ(levelForDepth(2.0, t), 1);
  EXPECT_EQ(levelForDepth(3.99, t), 1);
  EXPECT_EQ(levelForDepth(4.0, t), 2);
  EXPECT_EQ(levelForDepth(50.0, t), 2);  // clamped to s = 4
}

TEST(VoxelBlock, DefaultThresholdsReproduceTheThesisFormula) {
  const LevelThresholds t;
  for (double z = 0.05; z < 20.0; z += 0.0137) {
    // s(z) = 1 if z ≤ 1, else 2^⌊log2 z⌋ clamped to {1, 2, 4}
    const int s =
        z <= 1.0 ? 1 : std::min(4, std::max(1, 1 << static_cast<int>(std::floor(std::log2(z)))));
    EXPECT_EQ(levelScale(levelForDepth(z, t)), s) << "z = " << z;
  }
}

TEST(VoxelBlock, ThresholdsAreParameters) {
  const LevelThresholds t{1.0, 1.5};
  EXPECT_EQ(levelForDepth(0.9, t), 0);
  EXPECT_EQ(levelForDepth(1.2, t), 1);
  EXPECT_EQ(levelForDepth(1.6, t), 2);
}

TEST(VoxelBlock, NewBlockIsUnobserved) {
  VoxelBlock block;
  for (int n = 0; n < VoxelBlock::kVoxelCount; ++n) EXPECT_EQ(block.voxel(n).weight, 0.0f);
  for (int level = 0; level < kNumLevels; ++level) EXPECT_FALSE(block.hasLevel(level));
  EXPECT_EQ(block.voxelBytes(), 0u);
}

TEST(VoxelBlock, WritingAVoxelAllocatesItsLevelOnly) {
  VoxelBlock block;
  block.writableAt(2, 1, 0, 1).weight = 3.0f;  // flat index 576 + 1 + 4 = 581
  EXPECT_TRUE(block.hasLevel(2));
  EXPECT_FALSE(block.hasLevel(0) || block.hasLevel(1));
  EXPECT_EQ(block.voxelBytes(), 8u * 12u);
  EXPECT_EQ(block.voxel(581).weight, 3.0f);
  EXPECT_EQ(block.voxel(580).weight, 0.0f);
  block.writableVoxel(0).sdf_m = -0.5f;
  EXPECT_EQ(block.voxelBytes(), (512u + 8u) * 12u);
  // A deep copy: the copy's voxels are its own.
  VoxelBlock copy = block;
  copy.writableVoxel(581).weight = 1.0f;
  EXPECT_EQ(block.voxel(581).weight, 3.0f);
  EXPECT_EQ(copy.voxel(0).sdf_m, -0.5f);
  EXPECT_FALSE(copy.hasLevel(1));
  block.releaseLevel(0);
  EXPECT_FALSE(block.hasLevel(0));
  EXPECT_EQ(block.voxel(0).sdf_m, 0.0f);
  block.clearLevels();
  EXPECT_EQ(block.voxelBytes(), 0u);
}
