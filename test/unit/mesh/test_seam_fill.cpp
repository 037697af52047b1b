// fillFacesFromCoarserLevels(): the face voxels a block is meshed with where its own level is
// unobserved, worked by hand. (That the mesher's fast paths read the filled copies like the
// general path: test_block_mesher_fast_paths; that it closes the seams: test_block_mesher.)
#include <gtest/gtest.h>

#include <vector>

#include "stereo_fusion/mesh/BlockMesher.h"

using namespace stereo_fusion;

namespace {

/// A block whose 4³ level holds sdf = 0.01·I + 0.1·J + 1·K and red = 10·I at every voxel
/// (I, J, K), and whose 8³ level observes only voxel (0, 0, 0), at 0.5.
VoxelBlock linearCoarseBlock() {
  VoxelBlock block;
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        Voxel& v = block.writableAt(1, i, j, k);
        v.sdf_m = 0.01f * i + 0.1f * j + 1.0f * k;
        v.weight = 2.0f;
        v.r = static_cast<uint8_t>(10 * i);
      }
  Voxel& fine = block.writableAt(0, 0, 0, 0);
  fine.sdf_m = 0.5f;
  fine.weight = 3.0f;
  return block;
}

const Voxel& at(const std::vector<Voxel>& level0, int i, int j, int k) {
  return level0[i + 8 * (j + 8 * k)];
}

}  // namespace

TEST(SeamFill, FaceVoxelsTakeTheLinearFieldOfTheNextCoarserLevel) {
  const VoxelBlock block = linearCoarseBlock();
  std::vector<Voxel> filled;
  ASSERT_TRUE(fillFacesFromCoarserLevels(block, 0, &filled));
  ASSERT_EQ(filled.size(), 512u);
  // 8³ voxel i has its centre at (i + ½) finest voxels, 4³ voxel I at 2I + 1: in 4³ index units
  // the fine centre lies at (2i − 1) / 4, beyond the outer centres too (extrapolated):
  // i = 0 → −0.25, 1 → 0.25, 3 → 1.25, 4 → 1.75, 7 → 3.25.
  // (1, 0, 0), on the y = 0 and z = 0 faces: (0.25, −0.25, −0.25) → 0.0025 − 0.025 − 0.25 =
  // −0.2725, red 2.5 → 3.
  EXPECT_NEAR(at(filled, 1, 0, 0).sdf_m, -0.2725f, 1e-6f);
  EXPECT_EQ(at(filled, 1, 0, 0).weight, 1.0f);
  EXPECT_EQ(at(filled, 1, 0, 0).r, 3);
  // (3, 7, 2), on the y = 7 face: (1.25, 3.25, 0.75) → 0.0125 + 0.325 + 0.75 = 1.0875, red 12.5
  // → 13.
  EXPECT_NEAR(at(filled, 3, 7, 2).sdf_m, 1.0875f, 1e-6f);
  EXPECT_EQ(at(filled, 3, 7, 2).r, 13);
  // (7, 4, 4), on the x = 7 face: (3.25, 1.75, 1.75) → 0.0325 + 0.175 + 1.75 = 1.9575, red 32.5
  // → 33.
  EXPECT_NEAR(at(filled, 7, 4, 4).sdf_m, 1.9575f, 1e-6f);
  EXPECT_EQ(at(filled, 7, 4, 4).r, 33);
  // (0, 3, 0): red extrapolates to −2.5, clamped to 0.
  EXPECT_EQ(at(filled, 0, 3, 0).r, 0);
  // An observed voxel keeps its own value; an interior one stays unobserved.
  EXPECT_EQ(at(filled, 0, 0, 0).sdf_m, 0.5f);
  EXPECT_EQ(at(filled, 0, 0, 0).weight, 3.0f);
  EXPECT_EQ(at(filled, 3, 3, 3).weight, 0.0f);
  EXPECT_EQ(at(filled, 1, 1, 1).weight, 0.0f);
  // Every face voxel is filled (6·64 − 12·8 + 8 = 296 of them, one observed before).
  int face_observed = 0, inner_observed = 0;
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i) {
        const bool face = i == 0 || j == 0 || k == 0 || i == 7 || j == 7 || k == 7;
        (face ? face_observed : inner_observed) += at(filled, i, j, k).weight > 0.0f;
      }
  EXPECT_EQ(face_observed, 296);
  EXPECT_EQ(inner_observed, 0);
}

TEST(SeamFill, AnUnobservedCoarseSampleFallsThroughToTheCoarsestLevel) {
  VoxelBlock block = linearCoarseBlock();
  block.writableAt(1, 0, 0, 0).weight = 0.0f;  // weighed for 8³ voxels 0..2 on each axis
  for (int n = 0; n < 8; ++n) {
    Voxel& v = block.writableLevel(2)[n];
    v.sdf_m = -0.2f;
    v.weight = 1.0f;
    v.g = 7;
  }
  std::vector<Voxel> filled;
  ASSERT_TRUE(fillFacesFromCoarserLevels(block, 0, &filled));
  EXPECT_FLOAT_EQ(at(filled, 1, 0, 0).sdf_m, -0.2f);
  EXPECT_EQ(at(filled, 1, 0, 0).g, 7);
  EXPECT_NEAR(at(filled, 3, 7, 2).sdf_m, 1.0875f, 1e-6f);  // still from 4³
  // And a 4³ block fills from 2³: its face voxels all, from the one 2³ value.
  block.writableAt(1, 2, 0, 0).weight = 0.0f;
  ASSERT_TRUE(fillFacesFromCoarserLevels(block, 1, &filled));
  ASSERT_EQ(filled.size(), 64u);
  EXPECT_FLOAT_EQ(filled[2].sdf_m, -0.2f);
  EXPECT_FLOAT_EQ(filled[0].sdf_m, -0.2f);
  EXPECT_NEAR(filled[1].sdf_m, 0.01f, 1e-6f);  // observed: kept
}

TEST(SeamFill, NothingToFillLeavesTheCopyEmpty) {
  std::vector<Voxel> filled(5);
  // No coarser level allocated.
  VoxelBlock fine_only;
  fine_only.writableAt(0, 1, 1, 1).weight = 1.0f;
  EXPECT_FALSE(fillFacesFromCoarserLevels(fine_only, 0, &filled));
  EXPECT_TRUE(filled.empty());
  // The coarsest level has nothing coarser.
  const VoxelBlock block = linearCoarseBlock();
  EXPECT_FALSE(fillFacesFromCoarserLevels(block, 2, &filled));
  // Every face voxel already observed.
  EXPECT_FALSE(fillFacesFromCoarserLevels(block, 1, &filled));
  EXPECT_TRUE(filled.empty());
}

TEST(SeamFill, RefreshKeepsTheCopyOnlyWhenAskedAndTakesItsSigns) {
  // 8³ observes one voxel, at +0.5; 4³ is −0.3 everywhere: only the filled faces are negative.
  VoxelBlock block;
  block.writableAt(0, 0, 0, 0) = Voxel{0.5f, 1.0f, 0, 0, 0, 0};
  for (int n = 0; n < 64; ++n) block.writableLevel(1)[n] = Voxel{-0.3f, 1.0f, 0, 0, 0, 0};
  MeshingParams params;
  params.level_min_coverage = 1e-6;  // mesh at 8³ although it observes one voxel
  MeshBlockState state;
  refreshMeshLevel(block, params, &state);
  EXPECT_EQ(state.level, 0);
  EXPECT_TRUE(state.seam_filled);
  std::vector<Voxel> scratch;
  const Voxel* meshed = meshVoxels(block, state, &scratch);
  ASSERT_EQ(scratch.size(), 512u);
  EXPECT_EQ(meshed, scratch.data());
  EXPECT_FLOAT_EQ(scratch[1].sdf_m, -0.3f);
  EXPECT_NE(state.sign_bits & meshSignBit(0, false), 0) << "the sign bits read the filled copy";
  EXPECT_NE(state.sign_bits & meshSignBit(0, true), 0);
  params.fill_faces_from_coarser_levels = false;
  refreshMeshLevel(block, params, &state);
  EXPECT_FALSE(state.seam_filled);
  EXPECT_EQ(meshVoxels(block, state, &scratch), block.level(0));
  EXPECT_EQ(state.sign_bits & meshSignBit(0, false), 0);
}
