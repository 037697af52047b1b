// MapRegion (the shapes the ~clear_box / ~clear_sphere services take) worked by hand, and
// clearRegionVoxels() on hand-built blocks: which voxels of which level it forgets.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "TestSupport.h"
#include "stereo_fusion/map/RegionClearing.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {
/// Observes every voxel of every level of `block` (sdf = 0.01 m, weight 3).
void observeAll(VoxelBlock* block) {
  for (int level = 0; level < kNumLevels; ++level) {
    Voxel* voxels = block->writableLevel(level);
    for (int n = 0; n < levelVoxelCount(level); ++n) voxels[n] = Voxel{0.01f, 3.0f, 10, 20, 30, 0};
  }
}
}  // namespace

TEST(MapRegion, BoxAndSphereTestsHandWorked) {
  const MapRegion box = MapRegion::box({0, 0, 0}, {1, 2, 3});
  EXPECT_TRUE(box.contains({1, 2, 3}));  // the boundary belongs to the region
  EXPECT_FALSE(box.contains({1.001, 1, 1}));
  EXPECT_TRUE(
      box.intersects(Eigen::AlignedBox3d(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(5, 5, 5))));
  EXPECT_FALSE(
      box.intersects(Eigen::AlignedBox3d(Eigen::Vector3d(1.1, 0, 0), Eigen::Vector3d(5, 5, 5))));
  EXPECT_TRUE(
      box.containsBox(Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1))));
  EXPECT_FALSE(
      box.containsBox(Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 3.5))));

  // The box [1, 2]³ is √3 = 1.7321 m from the origin at its corner (1, 1, 1), and its far
  // corner (2, 2, 2) is √12 = 3.4641 m away.
  const Eigen::AlignedBox3d cube(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(2, 2, 2));
  EXPECT_TRUE(MapRegion::sphere({0, 0, 0}, 1.7321).intersects(cube));
  EXPECT_FALSE(MapRegion::sphere({0, 0, 0}, 1.7320).intersects(cube));
  EXPECT_TRUE(MapRegion::sphere({0, 0, 0}, 3.4642).containsBox(cube));
  EXPECT_FALSE(MapRegion::sphere({0, 0, 0}, 3.4640).containsBox(cube));
  // A box that straddles the centre: its nearest point is the centre itself.
  EXPECT_TRUE(MapRegion::sphere({1.5, 1.5, 1.5}, 0.01).intersects(cube));
  EXPECT_TRUE(MapRegion::sphere({0, 0, 1}, 0.5).contains({0.3, 0.4, 1.0}));  // 0.5 m away: on it
  EXPECT_FALSE(MapRegion::sphere({0, 0, 1}, 0.5).contains({0.3, 0.41, 1.0}));
}

TEST(MapRegion, InvalidRegionsSayWhatIsWrong) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(MapRegion::box({0, 0, 0}, {0, 0, 0}).validate(), "");  // a point is a valid box
  EXPECT_NE(MapRegion::box({0, 1, 0}, {1, 0, 1}).validate().find("min must not exceed its max"),
            std::string::npos);
  EXPECT_NE(MapRegion::box({nan, 0, 0}, {1, 1, 1}).validate().find("finite"), std::string::npos);
  EXPECT_NE(MapRegion::sphere({0, 0, 0}, 0.0).validate().find("radius must be positive"),
            std::string::npos);
  EXPECT_NE(MapRegion::sphere({0, 0, 0}, -1.0).validate().find("radius must be positive"),
            std::string::npos);
  EXPECT_NE(MapRegion::sphere({0, 0, 0}, INFINITY).validate().find("finite"), std::string::npos);
}

TEST(RegionClearing, ForgetsTheObservedVoxelsWhoseCentresLieInsideAtEveryLevel) {
  // Blocks are 8 · 0.02 = 0.16 m wide. Block (0,0,0) spans [0, 0.16)³, block (1,0,0)
  // [0.16, 0.32) × [0, 0.16)², block (5,0,0) lies far away.
  BlockOctree map(0.16);
  VoxelBlock* half = map.findOrAllocate({0, 0, 0});
  VoxelBlock* whole = map.findOrAllocate({1, 0, 0});
  VoxelBlock* far = map.findOrAllocate({5, 0, 0});
  observeAll(half);
  observeAll(whole);
  observeAll(far);
  // x ∈ [0.075, 0.33]: in block (0,0,0) the centres of level 0 at x = 0.09, 0.11, 0.13, 0.15
  // (i = 4..7), of level 1 at x = 0.10, 0.14 (i = 2, 3), of level 2 at x = 0.12 (i = 1): half
  // of every level, 256 + 32 + 4 = 292 voxels; block (1,0,0) entirely, 584 voxels.
  const MapRegion region = MapRegion::box({0.075, -1, -1}, {0.33, 1, 1});
  const RegionClearing result = clearRegionVoxels(region, &map);
  EXPECT_EQ(result.blocks_visited, 2u);
  EXPECT_EQ(result.voxels_cleared, 292u + 584u);
  ASSERT_EQ(result.changed, std::vector<BlockKey>({{0, 0, 0}}));
  ASSERT_EQ(result.emptied, std::vector<BlockKey>({{1, 0, 0}}));
  // The emptied block's three levels are freed (the caller erases the block itself).
  EXPECT_EQ(result.bytes_freed, 584u * sizeof(Voxel));
  EXPECT_EQ(whole->voxelBytes(), 0u);
  for (int level = 0; level < kNumLevels; ++level) {
    const int side = levelSide(level);
    ASSERT_TRUE(half->hasLevel(level));
    for (int k = 0; k < side; ++k)
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
          const Voxel& v = half->at(level, i, j, k);
          if (i >= side / 2) {
            EXPECT_EQ(v.weight, 0.0f) << "level " << level << " i " << i;
            EXPECT_EQ(v.sdf_m, 0.0f);
            EXPECT_EQ(v.r, 0);
          } else {
            EXPECT_EQ(v.weight, 3.0f) << "level " << level << " i " << i;
            EXPECT_EQ(v.g, 20);
          }
        }
  }
  // The block the region does not reach is untouched.
  for (int n = 0; n < VoxelBlock::kVoxelCount; ++n) EXPECT_EQ(far->voxel(n).weight, 3.0f);

  // Clearing again finds nothing left to forget.
  const RegionClearing again = clearRegionVoxels(region, &map);
  EXPECT_EQ(again.voxels_cleared, 0u);
  EXPECT_TRUE(again.changed.empty());
}

TEST(RegionClearing, ALevelLeftWithoutObservedVoxelsIsFreedAndUnobservedVoxelsAreNotCounted) {
  BlockOctree map(0.16);
  VoxelBlock* block = map.findOrAllocate({0, 0, 0});
  // Level 0: one observed voxel, inside the sphere; level 2: one inside, one outside.
  block->writableAt(0, 0, 0, 0) = Voxel{0.0f, 1.0f, 0, 0, 0, 0};  // centre (0.01, 0.01, 0.01)
  block->writableAt(2, 0, 0, 0) = Voxel{0.0f, 1.0f, 0, 0, 0, 0};  // centre (0.04, 0.04, 0.04)
  block->writableAt(2, 1, 1, 1) = Voxel{0.0f, 1.0f, 0, 0, 0, 0};  // centre (0.12, 0.12, 0.12)
  // Radius 0.08 around the origin: (0.04, 0.04, 0.04) is 0.0693 m away, (0.12, ...) 0.208 m.
  const RegionClearing result = clearRegionVoxels(MapRegion::sphere({0, 0, 0}, 0.08), &map);
  EXPECT_EQ(result.voxels_cleared, 2u);  // the 511 unobserved voxels of level 0 are not counted
  EXPECT_FALSE(block->hasLevel(0));
  EXPECT_TRUE(block->hasLevel(2));
  EXPECT_EQ(result.bytes_freed, 512u * sizeof(Voxel));
  EXPECT_EQ(result.changed, std::vector<BlockKey>({{0, 0, 0}}));
  EXPECT_TRUE(result.emptied.empty());
}
