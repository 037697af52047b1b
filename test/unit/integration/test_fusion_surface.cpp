// Fusing analytic surfaces: the SDF's zero crossing must lie on the true surface.
#include <gtest/gtest.h>

#include "TestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

constexpr double kVoxel = 0.02;

MapperConfig testConfig() {
  MapperConfig config;
  config.voxel_size_m = kVoxel;
  config.histogram_min_points = 0;
  return config;
}

struct PlaneScene {
  Eigen::Vector3d point{0.0, 0.0, 1.5};
  Eigen::Vector3d normal = Eigen::Vector3d(0.3, -0.2, -1.0).normalized();  // facing the camera
  sim::AnalyticScene scene;
  PlaneScene() { scene.add(sim::makePlane(point, normal)); }
  double distance(const Eigen::Vector3d& p) const { return std::abs(normal.dot(p - point)); }
};

struct SphereScene {
  Eigen::Vector3d centre{0.05, -0.03, 1.3};
  double radius = 0.3;
  sim::AnalyticScene scene;
  SphereScene() { scene.add(sim::makeSphere(centre, radius)); }
  double distance(const Eigen::Vector3d& p) const { return std::abs((p - centre).norm() - radius); }
  /// The crossing is in the well-observed band when the surface faces the camera at < 60°.
  bool wellObserved(const Eigen::Vector3d& p, const Eigen::Vector3d& eye) const {
    const Eigen::Vector3d n = (p - centre).normalized();
    return n.dot((eye - p).normalized()) > 0.5;
  }
};

/// Distances (in voxels of `level`) from all z-crossings at `level` to the surface.
template <typename Scene>
std::vector<double> crossingErrorsVox(const BlockOctree& map, const Scene& s, int level,
                                      const Eigen::Vector3d& eye, bool filter_grazing) {
  std::vector<double> errors;
  const double h = kVoxel * levelScale(level);
  for (const Eigen::Vector3d& p : zeroCrossings(map, level, 2)) {
    if constexpr (std::is_same_v<Scene, SphereScene>) {
      if (filter_grazing && !s.wellObserved(p, eye)) continue;
    }
    errors.push_back(s.distance(p) / h);
  }
  return errors;
}

}  // namespace

TEST(FusionSurface, PlaneZeroCrossingWithinTenthOfAVoxel) {
  const PlaneScene plane;
  Mapper mapper(testConfig());
  const Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const IntegrationResult r = mapper.integrate(renderFrame(plane.scene, vgaCamera(), pose));
  ASSERT_TRUE(r.accepted) << r.error;
  for (int level = 0; level < kNumLevels; ++level) {
    const std::vector<double> errors =
        crossingErrorsVox(mapper.tsdf(), plane, level, pose.translation(), false);
    ASSERT_GT(errors.size(), 1000u / (1 << (2 * level))) << "level " << level;
    const double worst = *std::max_element(errors.begin(), errors.end());
    EXPECT_LE(worst, 0.1) << "level " << level << ": " << errors.size() << " crossings";
    std::printf("[ plane ] level %d: %zu crossings, median %.4f, max %.4f voxel\n", level,
                errors.size(), median(errors), worst);
  }
}

TEST(FusionSurface, SphereZeroCrossingWithinTenthOfAVoxel) {
  const SphereScene sphere;
  Mapper mapper(testConfig());
  const Eigen::Vector3d eye(0, 0, 0);
  ASSERT_TRUE(
      mapper
          .integrate(renderFrame(sphere.scene, vgaCamera(),
                                 sim::lookAt(eye, sphere.centre, -Eigen::Vector3d::UnitY())))
          .accepted);
  // Crossings along all three axes over the cap facing the camera (< 60° from the view ray).
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> errors;
    for (const Eigen::Vector3d& p : zeroCrossings(mapper.tsdf(), 0, axis))
      if (sphere.wellObserved(p, eye)) errors.push_back(sphere.distance(p) / kVoxel);
    ASSERT_GT(errors.size(), 150u) << "axis " << axis;
    const double worst = *std::max_element(errors.begin(), errors.end());
    std::printf("[ sphere ] axis %d: %zu crossings, median %.4f, max %.4f voxel\n", axis,
                errors.size(), median(errors), worst);
    EXPECT_LE(worst, 0.1) << "axis " << axis;
  }
}

TEST(FusionSurface, SphereFromThreeViews) {
  // Eq. 3.15 measures distance along each view's ray, i.e. d_perp / cos(angle of incidence).
  // Views at different angles therefore disagree on the SDF's slope (not on its zero), and the
  // Steinbrücker weights mix them differently in front of and behind the surface, which moves
  // the linearly interpolated crossing slightly. Measured: median ≈ 0.01, max ≈ 0.15 voxel.
  const SphereScene sphere;
  Mapper mapper(testConfig());
  std::vector<Eigen::Vector3d> eyes = {{0, 0, 0}, {0.5, 0.2, 0.3}, {-0.4, -0.3, 0.2}};
  for (const auto& eye : eyes)
    ASSERT_TRUE(
        mapper
            .integrate(renderFrame(sphere.scene, vgaCamera(),
                                   sim::lookAt(eye, sphere.centre, -Eigen::Vector3d::UnitY())))
            .accepted);
  const std::vector<double> errors = crossingErrorsVox(mapper.tsdf(), sphere, 0, eyes[0], true);
  ASSERT_GT(errors.size(), 300u);
  const double worst = *std::max_element(errors.begin(), errors.end());
  std::printf("[ sphere, 3 views ] %zu crossings, median %.4f, max %.4f voxel\n", errors.size(),
              median(errors), worst);
  EXPECT_LE(median(errors), 0.05);
  EXPECT_LE(worst, 0.2);
}

TEST(FusionSurface, NoisyPlaneFusesToQuarterVoxelAfter30Frames) {
  const PlaneScene plane;
  Mapper mapper(testConfig());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.03, 0.03);
  for (int f = 0; f < 30; ++f) {
    const Eigen::Vector3d eye(jitter(rng), jitter(rng), jitter(rng));
    const Eigen::Isometry3d pose = sim::lookAt(eye, plane.point, -Eigen::Vector3d::UnitY());
    ASSERT_TRUE(
        mapper.integrate(renderFrame(plane.scene, vgaCamera(), pose, 0.3, 100 + f)).accepted);
  }
  const std::vector<double> errors =
      crossingErrorsVox(mapper.tsdf(), plane, 0, Eigen::Vector3d::Zero(), false);
  ASSERT_GT(errors.size(), 1000u);
  const double med = median(errors);
  std::printf("[ noisy plane ] σ = 0.3 px, 30 frames: %zu crossings, median %.4f voxel\n",
              errors.size(), med);
  EXPECT_LE(med, 0.25);
}

TEST(FusionSurface, NoisySphereFusesToQuarterVoxelAfter30Frames) {
  const SphereScene sphere;
  Mapper mapper(testConfig());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  for (int f = 0; f < 30; ++f) {
    const Eigen::Vector3d eye(jitter(rng), jitter(rng), jitter(rng));
    ASSERT_TRUE(mapper
                    .integrate(renderFrame(
                        sphere.scene, vgaCamera(),
                        sim::lookAt(eye, sphere.centre, -Eigen::Vector3d::UnitY()), 0.3, 200 + f))
                    .accepted);
  }
  const std::vector<double> errors =
      crossingErrorsVox(mapper.tsdf(), sphere, 0, Eigen::Vector3d::Zero(), true);
  ASSERT_GT(errors.size(), 300u);
  const double med = median(errors);
  std::printf("[ noisy sphere ] σ = 0.3 px, 30 frames: %zu crossings, median %.4f voxel\n",
              errors.size(), med);
  EXPECT_LE(med, 0.25);
}

TEST(FusionSurface, SignConventionNegativeInFront) {
  // Fronto-parallel plane at 1.5 m seen from the origin: voxels nearer than the plane hold
  // negative distances, voxels just behind it positive ones.
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 1.5}, {0, 0, -1}));
  Mapper mapper(testConfig());
  ASSERT_TRUE(
      mapper.integrate(renderFrame(scene, vgaCamera(), Eigen::Isometry3d::Identity())).accepted);
  int front = 0, behind = 0;
  for (const VoxelBlock* b : mapper.tsdf().blocks()) {
    for (int k = 0; k < 8; ++k)
      for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
          const Voxel& v = b->at(0, i, j, k);
          if (v.weight <= 0) continue;
          const double z = voxelCentre(mapper.tsdf(), b->key, 0, i, j, k).z();
          if (z < 1.5 - 0.5 * kVoxel) {
            EXPECT_LT(v.sdf_m, 0.0f);
            ++front;
          } else if (z > 1.5 + 0.5 * kVoxel) {
            EXPECT_GT(v.sdf_m, 0.0f);
            EXPECT_LE(v.sdf_m, 4 * kVoxel + 1e-6);  // never beyond Φ behind
            ++behind;
          }
        }
  }
  EXPECT_GT(front, 1000);
  EXPECT_GT(behind, 1000);
}

TEST(FusionSurface, CoarseLevelsGetABandOfTheirOwnVoxels) {
  // With a 1-voxel truncation, near measurements must still give the 4³ and 2³ levels values
  // on both sides of the surface: Φ is at least 2 voxels of the level being updated. The
  // crossing count per area then matches across levels (a level-L voxel covers 4^L of the
  // 8³ level's crossings on a plane).
  const PlaneScene plane;
  MapperConfig config = testConfig();
  config.truncation_vox = 1.0;
  config.weight_falloff_start_vox = 0.5;
  Mapper mapper(config);
  ASSERT_TRUE(mapper.integrate(renderFrame(plane.scene, vgaCamera(), Eigen::Isometry3d::Identity()))
                  .accepted);
  const double fine = static_cast<double>(zeroCrossings(mapper.tsdf(), 0, 2).size());
  ASSERT_GT(fine, 3000);
  for (int level = 1; level < kNumLevels; ++level) {
    const double scaled =
        static_cast<double>(zeroCrossings(mapper.tsdf(), level, 2).size()) * (1 << (2 * level));
    std::printf("[ coarse band ] level %d: %.0f crossings per level-0 area vs %.0f at level 0\n",
                level, scaled, fine);
    EXPECT_GT(scaled, 0.8 * fine) << "level " << level;
  }
}

TEST(FusionSurface, FarMeasurementsOnlyReachCoarseLevels) {
  // A wall at 5 m is fused at level 2 only (s = 4): the 8³ and 4³ levels stay unobserved.
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 5.0}, {0, 0, -1}));
  Mapper mapper(testConfig());
  ASSERT_TRUE(
      mapper.integrate(renderFrame(scene, vgaCamera(), Eigen::Isometry3d::Identity())).accepted);
  size_t observed[kNumLevels] = {0, 0, 0};
  for (const VoxelBlock* b : mapper.tsdf().blocks())
    for (int level = 0; level < kNumLevels; ++level)
      for (int n = 0; n < levelVoxelCount(level); ++n)
        observed[level] += b->level(level)[n].weight > 0;
  EXPECT_EQ(observed[0], 0u);
  EXPECT_EQ(observed[1], 0u);
  EXPECT_GT(observed[2], 100u);
  // Far measurements allocate only the level they update: 96 bytes of voxels per block.
  for (const VoxelBlock* b : mapper.tsdf().blocks()) {
    EXPECT_FALSE(b->hasLevel(0) || b->hasLevel(1)) << b->key;
    EXPECT_EQ(b->voxelBytes(), 8 * sizeof(Voxel)) << b->key;
  }
  // The coarse surface is still accurate to a tenth of its voxel.
  PlaneScene far_plane;
  far_plane.point = {0, 0, 5.0};
  far_plane.normal = {0, 0, -1};
  const auto errors = crossingErrorsVox(mapper.tsdf(), far_plane, 2, {0, 0, 0}, false);
  ASSERT_GT(errors.size(), 100u);
  EXPECT_LE(*std::max_element(errors.begin(), errors.end()), 0.1);
}

TEST(FusionSurface, AFartherViewRefinesTheFineLevelANearViewAllocated) {
  // A wall at z = 1.8 m seen from the origin (level 0, the thesis' 2 m switch) and then from
  // 0.5 m farther back (2.3 m: level 1). With update_allocated_finer_level the second view
  // also updates the level-0 voxels the first one allocated, with its own band Φ₁ = 8 voxels
  // and a quarter of its weight (kFinerLevelWeightScale): those it observes get weight
  // 1 + 1/4 and keep the wall's exact distance (frontal view, voxels
  // within δ in front: the along-ray distance is the distance to the wall up to the ray's
  // slant, ≤ 1.6e-3 of it within 0.1 m of the axis). Without the option they keep weight 1. Neither
  // run allocates level 0 in a block the first view did not reach.
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 1.8}, {0, 0, -1}));
  for (const bool refine : {true, false}) {
    SCOPED_TRACE(refine ? "update_allocated_finer_level" : "thesis levels only");
    MapperConfig config = testConfig();
    config.level_mode = LevelMode::kDepth;
    config.update_allocated_finer_level = refine;
    Mapper mapper(config);
    Eigen::Isometry3d near_pose = Eigen::Isometry3d::Identity(),
                      far_pose = Eigen::Isometry3d::Identity();
    far_pose.translation() = Eigen::Vector3d(0, 0, -0.5);
    ASSERT_TRUE(mapper.integrate(renderFrame(scene, vgaCamera(), near_pose)).accepted);
    std::vector<BlockKey> level0_blocks;
    for (const VoxelBlock* b : mapper.tsdf().blocks())
      if (b->hasLevel(0)) level0_blocks.push_back(b->key);
    ASSERT_GT(level0_blocks.size(), 100u);
    ASSERT_TRUE(mapper.integrate(renderFrame(scene, vgaCamera(), far_pose)).accepted);
    size_t refined = 0, near_only = 0, level0_after = 0;
    for (const VoxelBlock* b : mapper.tsdf().blocks()) {
      if (!b->hasLevel(0)) continue;
      ++level0_after;
      EXPECT_NE(std::find(level0_blocks.begin(), level0_blocks.end(), b->key), level0_blocks.end())
          << b->key;
      const Eigen::Vector3d origin = mapper.tsdf().blockOrigin(b->key);
      for (int k = 0; k < 8; ++k)
        for (int j = 0; j < 8; ++j)
          for (int i = 0; i < 8; ++i) {
            const Voxel& v = b->level(0)[VoxelBlock::indexInLevel(8, i, j, k)];
            const Eigen::Vector3d centre =
                origin + kVoxel * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5);
            const double wall_distance_m = centre.z() - 1.8;  // negative in front
            // Within δ = 1 voxel in front of the wall and near the optical axis: weight 1 per view.
            if (!(wall_distance_m < 0 && wall_distance_m > -kVoxel) ||
                centre.head<2>().norm() > 0.1)
              continue;
            if (v.weight == 1.25f) ++refined;
            if (v.weight == 1.0f) ++near_only;
            EXPECT_NEAR(v.sdf_m, wall_distance_m, 2e-3 * std::abs(wall_distance_m) + 1e-6);
          }
    }
    EXPECT_EQ(level0_after, level0_blocks.size());
    if (refine) {
      EXPECT_GT(refined, 60u);  // the ~79 voxels of the 0.1 m disc
      EXPECT_EQ(near_only, 0u);
    } else {
      EXPECT_EQ(refined, 0u);
      EXPECT_GT(near_only, 60u);
    }
  }
}
