// The AVX2 mesh-level refresh against the plain one (chooseMeshLevel(), the face fill, then
// refreshMeshSigns()): same level, fill and sign bits on random blocks with unobserved voxels, ±0,
// values in [−1e-30, 0), NaN, in all three levels and at several coverage shares; and on blocks
// with a single observed voxel anywhere, which pins each voxel to its region.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "stereo_fusion/mesh/BlockMesher.h"
#include "stereo_fusion/util/CpuFeatures.h"

using namespace stereo_fusion;

namespace {

/// A signed distance, often one whose sign the refresh must classify with care.
float randomSdf(std::mt19937& rng) {
  const float specials[] = {0.0f,
                            -0.0f,
                            1e-31f,
                            -1e-31f,
                            -1e-30f,
                            -1.0000001e-30f,
                            -2e-30f,
                            1e-40f,
                            -1e-40f,
                            1e-30f,
                            0.5f,
                            -0.5f,
                            std::numeric_limits<float>::quiet_NaN(),
                            std::numeric_limits<float>::infinity(),
                            -std::numeric_limits<float>::infinity()};
  std::uniform_int_distribution<int> pick(
      0, static_cast<int>(sizeof(specials) / sizeof(specials[0])) - 1);
  std::uniform_real_distribution<float> value(-0.1f, 0.1f);
  return std::uniform_real_distribution<float>(0.0f, 1.0f)(rng) < 0.3f ? specials[pick(rng)]
                                                                       : value(rng);
}

/// A weight: observed (> 0, denormals included) or not (0, −0, NaN, negative).
float randomWeight(std::mt19937& rng, float observed_share) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  if (unit(rng) < observed_share) return unit(rng) < 0.1f ? 1e-42f : 0.5f + 20.0f * unit(rng);
  const float unobserved[] = {0.0f, -0.0f, 0.0f, 0.0f, std::numeric_limits<float>::quiet_NaN(),
                              -1.0f};
  return unobserved[std::uniform_int_distribution<int>(0, 5)(rng)];
}

/// A block whose levels are observed in random shares, so that every level gets chosen.
VoxelBlock randomBlock(std::mt19937& rng) {
  VoxelBlock block;
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int level = 0; level < kNumLevels; ++level) {
    // Often empty or full, so that counts at the coverage thresholds come up too.
    const float r = unit(rng);
    const float share = r < 0.2f ? 0.0f : r < 0.35f ? 1.0f : unit(rng);
    for (int n = 0; n < levelVoxelCount(level); ++n) {
      Voxel& v = block.writableLevel(level)[n];
      v.sdf_m = randomSdf(rng);
      v.weight = randomWeight(rng, share);
      v.r = static_cast<uint8_t>(n);
    }
  }
  return block;
}

bool sameVoxels(const std::vector<Voxel>& a, const std::vector<Voxel>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Voxel)) == 0);
}

void expectSameRefresh(const VoxelBlock& block, double coverage, bool fill = true) {
  MeshingParams params;
  params.level_min_coverage = coverage;
  params.fill_faces_from_coarser_levels = fill;
  // Stale values the refresh must overwrite.
  static std::mt19937 rng(7);
  MeshBlockState stale;
  stale.level = static_cast<int8_t>(std::uniform_int_distribution<int>(0, kNumLevels - 1)(rng));
  stale.sign_bits = static_cast<uint16_t>(rng());
  stale.seam_filled = std::uniform_int_distribution<int>(0, 1)(rng) == 1;
  MeshBlockState plain = stale, avx2 = stale, dispatched = stale;
  refreshMeshLevelScalar(block, params, &plain);
  refreshMeshLevelAvx2(block, params, &avx2);
  refreshMeshLevel(block, params, &dispatched);
  ASSERT_EQ(plain.level, chooseMeshLevel(block, coverage));
  ASSERT_EQ(avx2.level, plain.level) << "coverage " << coverage;
  ASSERT_EQ(avx2.sign_bits, plain.sign_bits) << "level " << int{plain.level};
  ASSERT_EQ(dispatched.level, plain.level);
  ASSERT_EQ(dispatched.sign_bits, plain.sign_bits);
  std::vector<Voxel> expected_fill;
  const bool filled = fill && fillFacesFromCoarserLevels(block, plain.level, &expected_fill);
  ASSERT_EQ(plain.seam_filled, filled);
  ASSERT_EQ(avx2.seam_filled, filled);
  ASSERT_EQ(dispatched.seam_filled, filled);
  if (filled) {  // what the mesher then reads
    std::vector<Voxel> scratch;
    const Voxel* meshed = meshVoxels(block, plain, &scratch);
    ASSERT_TRUE(sameVoxels(std::vector<Voxel>(meshed, meshed + levelVoxelCount(plain.level)),
                           expected_fill));
  }
}

TEST(MeshLevelRefresh, Avx2MatchesPlainOnRandomBlocks) {
  if (!avx2Supported()) GTEST_SKIP() << "no AVX2 on this CPU";
  std::mt19937 rng(20261122);
  int chosen[kNumLevels] = {}, filled = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const VoxelBlock block = randomBlock(rng);
    for (double coverage : {0.0, 1e-6, 0.5, 0.8, 1.0}) {
      ASSERT_NO_FATAL_FAILURE(expectSameRefresh(block, coverage, trial % 4 != 3))
          << "trial " << trial;
      MeshBlockState state;
      refreshMeshLevel(block, MeshingParams{0.02, 4.0, coverage}, &state);
      filled += state.seam_filled;
      ++chosen[chooseMeshLevel(block, coverage)];
    }
  }
  // The comparison means little unless every level's sign pass ran many times.
  for (int level = 0; level < kNumLevels; ++level)
    EXPECT_GT(chosen[level], 1000) << "level " << level;
  EXPECT_GT(filled, 1000);  // and the sign pass over a filled copy
}

TEST(MeshLevelRefresh, Avx2MatchesPlainForEverySingleVoxel) {
  if (!avx2Supported()) GTEST_SKIP() << "no AVX2 on this CPU";
  for (int index = 0; index < VoxelBlock::kVoxelCount; ++index) {
    for (float sdf : {-0.25f, 0.25f, -1e-31f, -0.0f}) {
      VoxelBlock block;
      block.writableVoxel(index).sdf_m = sdf;
      block.writableVoxel(index).weight = 1.0f;
      // The only observed voxel decides the level: its sign bits come from that voxel alone.
      ASSERT_NO_FATAL_FAILURE(expectSameRefresh(block, 0.8)) << "voxel " << index << " sdf " << sdf;
    }
  }
}

}  // namespace
