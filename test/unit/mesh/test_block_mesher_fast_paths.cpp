// The mesher's fast paths (uniform-neighbourhood sampling by voxel index, box pre-tests on
// voxel bit masks) against its general path (MesherPaths::kGeneralOnly), bit for bit,
// on random neighbourhoods built to hit their edge cases: absent blocks, unobserved voxels,
// ±0, values too small to keep their sign through the weighted sums, values at the
// truncation threshold of every level.
#include <gtest/gtest.h>

#include <cstring>
#include <Eigen/Geometry>
#include <limits>
#include <random>

#include "QuickMode.h"
#include "stereo_fusion/mesh/BlockMesher.h"

using namespace stereo_fusion;

namespace {

constexpr double kVoxel = 0.02;
constexpr double kTruncationVox = 4.0;
constexpr int kClusterSide = 4;  // blocks per axis

/// Bitwise equality of two float vectors (−0 ≠ +0, NaN payloads compared).
template <typename T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

/// A value for one voxel: mostly a tilted plane's distance plus noise, sometimes one of the
/// values the fast paths must treat exactly like the general path.
float voxelValue(std::mt19937& rng, const Eigen::Vector3d& centre, const Eigen::Vector3d& normal,
                 double offset, double noise_vox) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  if (unit(rng) < 0.25) {
    const float phi = static_cast<float>(kTruncationVox * kVoxel);
    const float band = 0.99f * phi;
    const float specials[] = {
        0.0f, -0.0f, 1e-31f, -1e-31f, -1e-30f, -2e-30f, 1e-40f, -1e-40f, band, -band, 2 * band,
        -2 * band, 4 * band, -4 * band, phi, -phi, 4 * phi, -4 * phi, std::nextafter(band, 0.0f),
        std::nextafter(-band, 0.0f), std::nextafter(2 * band, 1.0f),
        std::nextafter(-4 * band, -1.0f),
        // Negative, yet the 1/s-weighted sums of coarse levels round them to −0.
        -std::numeric_limits<float>::denorm_min(), -3 * std::numeric_limits<float>::denorm_min()};
    return specials[std::uniform_int_distribution<size_t>(0, std::size(specials) - 1)(rng)];
  }
  std::normal_distribution<double> noise(0.0, noise_vox * kVoxel);
  const double d = normal.dot(centre) - offset + noise(rng);
  const double phi = kTruncationVox * 4 * kVoxel;
  return static_cast<float>(std::clamp(d, -phi, phi));
}

struct Trial {
  int owners_uniform = 0, owners_mixed = 0, face_filled_blocks = 0;
  size_t triangles = 0;
};

/// Builds one random cluster and compares every block's submesh from both paths. The voxels
/// hold a plane's distance plus Gaussian noise of `noise_vox` voxels.
/// `layered`: each block also holds every level coarser than its own (as fusion leaves them), so
/// the mesher samples face-filled copies (fillFacesFromCoarserLevels()).
void runTrial(uint32_t seed, bool uniform_levels, Trial* totals, double noise_vox = 0.3,
              bool layered = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double block_size = kFinestSide * kVoxel;
  BlockOctree map(block_size);
  MeshStates states;  // the mesher's per-block state, as MeshStore keeps it
  const Eigen::Vector3d normal =
      Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized();
  const double offset = normal.dot(Eigen::Vector3d::Constant(kClusterSide * block_size / 2)) +
                        (unit(rng) - 0.5) * block_size;
  const double presence = 0.7 + 0.3 * unit(rng);
  const double observed_share = 0.6 + 0.4 * unit(rng);
  const int shared_level = std::uniform_int_distribution<int>(0, kNumLevels - 1)(rng);
  for (int z = 0; z < kClusterSide; ++z)
    for (int y = 0; y < kClusterSide; ++y)
      for (int x = 0; x < kClusterSide; ++x) {
        if (unit(rng) > presence) continue;
        VoxelBlock* block = map.findOrAllocate({x, y, z});
        const int level = uniform_levels
                              ? shared_level
                              : std::uniform_int_distribution<int>(0, kNumLevels - 1)(rng);
        for (int written = level; written <= (layered ? kNumLevels - 1 : level); ++written) {
          const int side = levelSide(written);
          const double h = block_size / side;
          for (int k = 0; k < side; ++k)
            for (int j = 0; j < side; ++j)
              for (int i = 0; i < side; ++i) {
                if (unit(rng) > observed_share) continue;
                const Eigen::Vector3d centre =
                    map.blockOrigin(block->key) + Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5) * h;
                Voxel& v = block->writableAt(written, i, j, k);
                v.sdf_m = voxelValue(rng, centre, normal, offset, noise_vox);
                v.weight = 1.0f;
                v.r = static_cast<uint8_t>(rng());
                v.g = static_cast<uint8_t>(rng());
                v.b = static_cast<uint8_t>(rng());
              }
        }
        // `level` is the finest level holding data, so it is the level chosen (any coverage > 0);
        // a block with no observed voxel falls back to the coarsest level, which the mesher must
        // handle too.
        states.fit(map);
        refreshMeshLevel(*block, MeshingParams{kVoxel, kTruncationVox, 1e-6}, &states[*block]);
        totals->face_filled_blocks += states[*block].seam_filled;
      }
  const MeshingParams params{kVoxel, kTruncationVox, 1e-6};
  const BlockMesher fast(params), general(params, MesherPaths::kGeneralOnly);
  for (VoxelBlock* owner : map.blocks()) {
    SubMesh a, b;
    fast.mesh(map, states, *owner, &a);
    general.mesh(map, states, *owner, &b);
    bool uniform = true;
    for (int d = 1; d < 8; ++d)
      if (const VoxelBlock* nb = map.find(owner->key.offset(d & 1, (d >> 1) & 1, (d >> 2) & 1)))
        uniform &= states[*nb].level == states[*owner].level;
    ++(uniform ? totals->owners_uniform : totals->owners_mixed);
    totals->triangles += b.triangles.size();
    const std::string where = "seed " + std::to_string(seed) + ", owner (" +
                              std::to_string(owner->key.x) + ", " + std::to_string(owner->key.y) +
                              ", " + std::to_string(owner->key.z) + ")";
    ASSERT_EQ(a.triangles, b.triangles) << where;
    ASSERT_TRUE(sameBytes(a.positions, b.positions)) << where;
    ASSERT_TRUE(sameBytes(a.normals, b.normals)) << where;
    ASSERT_EQ(a.colors, b.colors) << where;
    ASSERT_EQ(a.level, b.level) << where;
  }
}

}  // namespace

TEST(BlockMesherFastPaths, SameBitsAsTheGeneralPathOnRandomNeighbourhoods) {
  Trial totals;
  const int trials = test::quickMode() ? 40 : 150;
  for (int t = 0; t < trials; ++t) {
    runTrial(1000 + t, /*uniform_levels=*/t % 2 == 0, &totals);
    if (HasFatalFailure()) return;
  }
  std::printf("[ fast paths ] %d uniform and %d mixed neighbourhoods, %zu triangles: identical\n",
              totals.owners_uniform, totals.owners_mixed, totals.triangles);
  // The comparison means something only if both kinds of neighbourhood produced triangles
  // (per trial ≈ 30 uniform and 24 mixed owners and 2 000+ triangles; quick mode runs fewer).
  EXPECT_GT(totals.owners_uniform, 20 * trials);
  EXPECT_GT(totals.owners_mixed, 15 * trials);
  EXPECT_GT(totals.triangles, 1000u * trials);
}

// Blocks holding their coarser levels too: unobserved face voxels of the finer ones are filled,
// and the fast paths' masks and sign bits must read the filled copies as samplePoint() does.
TEST(BlockMesherFastPaths, SameBitsWithFacesFilledFromCoarserLevels) {
  Trial totals;
  const int trials = test::quickMode() ? 20 : 80;
  for (int t = 0; t < trials; ++t) {
    runTrial(9000 + t, /*uniform_levels=*/t % 2 == 0, &totals, /*noise_vox=*/t % 4 < 2 ? 0.3 : 2.0,
             /*layered=*/true);
    if (HasFatalFailure()) return;
  }
  std::printf(
      "[ fast paths, face-filled ] %d uniform and %d mixed neighbourhoods, %d filled blocks, %zu "
      "triangles: "
      "identical\n",
      totals.owners_uniform, totals.owners_mixed, totals.face_filled_blocks, totals.triangles);
  EXPECT_GT(totals.face_filled_blocks, 10 * trials);  // ≈ 17 per trial
  EXPECT_GT(totals.owners_mixed, 10 * trials);
  EXPECT_GT(totals.triangles, 1000u * trials);
}

// Noise of several voxels flips signs voxel by voxel near the plane, so boxes on faces between
// levels often have one sign at their corners and the other at a hanging point: the case the
// box-support pre-test (one sign over every voxel a box's points may weigh) must leave alone.
TEST(BlockMesherFastPaths, SameBitsWithSignsFlippingVoxelByVoxelBetweenLevels) {
  Trial totals;
  const int trials = test::quickMode() ? 20 : 80;
  for (int t = 0; t < trials; ++t) {
    runTrial(5000 + t, /*uniform_levels=*/false, &totals, /*noise_vox=*/2.0);
    if (HasFatalFailure()) return;
  }
  std::printf("[ fast paths, noisy ] %d mixed neighbourhoods, %zu triangles: identical\n",
              totals.owners_mixed, totals.triangles);
  EXPECT_GT(totals.owners_mixed, 15 * trials);
  EXPECT_GT(totals.triangles, 1000u * trials);
}
