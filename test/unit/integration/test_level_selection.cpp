// Level switch depths from the camera's depth error (level_mode noise) or fixed (depth).
#include <gtest/gtest.h>

#include <cmath>

#include "MeshTestSupport.h"
#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/integration/LevelSelection.h"
#include "stereo_fusion/integration/MeasurementImage.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

TEST(LevelSelection, NoiseModeSwitchesWhereTheDepthErrorReachesTheVoxelEdge) {
  MapperConfig config;  // level_mode noise
  config.voxel_size_m = 0.02;
  config.disparity_noise_px = 0.15;
  // f·b = 576 · 0.12 = 69.12: z1 = sqrt(0.02 · 69.12 / 0.15) = sqrt(9.216), z2 = sqrt(18.432)
  const LevelThresholds t =
      levelThresholdsFor(stageConfigs(config).pipeline.measurement.levels, 69.12);
  EXPECT_NEAR(t.scale2_min_depth_m, 3.035787, 1e-6);
  EXPECT_NEAR(t.scale4_min_depth_m, 4.293251, 1e-6);
  // At each switch the depth error equals that level's voxel edge: 2 cm and 4 cm.
  EXPECT_NEAR(depthNoiseM(t.scale2_min_depth_m, 69.12, 0.15), 0.02, 1e-12);
  EXPECT_NEAR(depthNoiseM(t.scale4_min_depth_m, 69.12, 0.15), 0.04, 1e-12);
  // A long-baseline camera (KITTI: f·b ≈ 386) at 10 cm stays fine to 16 m; a noisier source
  // (σ_d four times larger) goes coarse at half the depth.
  config.voxel_size_m = 0.10;
  EXPECT_NEAR(levelThresholdsFor(stageConfigs(config).pipeline.measurement.levels, 386.14)
                  .scale2_min_depth_m,
              std::sqrt(0.10 * 386.14 / 0.15), 1e-9);
  config.disparity_noise_px = 0.60;
  EXPECT_NEAR(levelThresholdsFor(stageConfigs(config).pipeline.measurement.levels, 386.14)
                  .scale2_min_depth_m,
              0.5 * std::sqrt(0.10 * 386.14 / 0.15), 1e-9);
}

TEST(LevelSelection, CoarseDisparityStepsRaiseTheNoiseToTheirRoundingError) {
  MapperConfig config;  // level_mode noise, σ_d 0.15 px
  config.voxel_size_m = 0.02;
  // SGBM's 1/16 px steps round by 0.018 px (1σ): below σ_d, nothing changes.
  EXPECT_DOUBLE_EQ(disparityNoisePx(stageConfigs(config).pipeline.measurement.levels, 1.0 / 16.0),
                   0.15);
  EXPECT_DOUBLE_EQ(disparityNoisePx(stageConfigs(config).pipeline.measurement.levels, 0.0), 0.15)
      << "unknown step";
  EXPECT_EQ(levelThresholdsFor(stageConfigs(config).pipeline.measurement.levels, 69.12, 1.0 / 16.0)
                .scale2_min_depth_m,
            levelThresholdsFor(stageConfigs(config).pipeline.measurement.levels, 69.12)
                .scale2_min_depth_m);
  // Whole-pixel disparities: σ_d = 1/√12 = 0.288675 px, so z1 = sqrt(0.02 · 69.12 / 0.288675)
  // = sqrt(4.788774) = 2.188327 m and z2 = sqrt(9.577548) = 3.094761 m.
  EXPECT_NEAR(disparityNoisePx(stageConfigs(config).pipeline.measurement.levels, 1.0), 0.2886751,
              1e-7);
  const LevelThresholds whole =
      levelThresholdsFor(stageConfigs(config).pipeline.measurement.levels, 69.12, 1.0);
  EXPECT_NEAR(whole.scale2_min_depth_m, 2.188327, 1e-6);
  EXPECT_NEAR(whole.scale4_min_depth_m, 3.094761, 1e-6);
  // The configured depths ignore it.
  config.level_mode = LevelMode::kDepth;
  EXPECT_EQ(levelThresholdsFor(stageConfigs(config).pipeline.measurement.levels, 69.12, 1.0)
                .scale2_min_depth_m,
            config.levels.scale2_min_depth_m);
}

TEST(LevelSelection, DepthModeKeepsTheConfiguredDepths) {
  MapperConfig config;
  config.level_mode = LevelMode::kDepth;
  config.levels.scale2_min_depth_m = 1.5;
  config.levels.scale4_min_depth_m = 3.5;
  for (double fb : {10.0, 69.12, 400.0}) {
    const LevelThresholds t =
        levelThresholdsFor(stageConfigs(config).pipeline.measurement.levels, fb);
    EXPECT_EQ(t.scale2_min_depth_m, 1.5);
    EXPECT_EQ(t.scale4_min_depth_m, 3.5);
  }
}

// End to end: a wall at 2.5 m is fused at 4³ with the thesis' depths (2 m) and at the finest
// level when the camera's error says its data are good to 3 m.
TEST(LevelSelection, TheMapperFusesAtTheLevelTheFramesCameraSelects) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 2.5}, {0, 0, -1}));
  const StereoCamera camera =
      *StereoCamera::create(320, 240, 288.0, 288.0, 159.5, 119.5, 0.24);  // f·b = 69.12
  StereoFrame frame = renderFrame(scene, camera, Eigen::Isometry3d::Identity());
  frame.timestamp_s = 1.0;
  auto levelsAllocated = [&](const MapperConfig& config) {
    Mapper mapper(config);
    EXPECT_TRUE(mapper.integrate(frame).accepted);
    int mask = 0;
    for (const VoxelBlock* b : mapper.tsdf().blocksSortedByKey())
      for (int level = 0; level < kNumLevels; ++level)
        if (b->hasLevel(level)) mask |= 1 << level;
    return mask;
  };
  MapperConfig depth_mode;
  depth_mode.level_mode = LevelMode::kDepth;
  EXPECT_EQ(levelsAllocated(depth_mode), 0b110) << "2.5 m is past the thesis' 2 m: 4³ and coarser";
  MapperConfig noise_mode;  // σ_d = 0.15 px: level 1 from 3.04 m
  EXPECT_EQ(levelsAllocated(noise_mode), 0b111)
      << "good data at 2.5 m stays at 8³ (and updates the coarser levels)";
  // Whole-pixel disparities (delta_d = 1): σ_d ≥ 0.289 px, level 1 from 2.19 m.
  frame.disparity_step_px = 1.0;
  EXPECT_EQ(levelsAllocated(noise_mode), 0b110) << "rounded disparities at 2.5 m go to 4³";
  frame.disparity_step_px = 0.0;
  noise_mode.disparity_noise_px = 0.6;  // level 1 from 1.52 m, level 2 from 2.15 m
  EXPECT_EQ(levelsAllocated(noise_mode), 0b100);
  // A step that is no resolution is refused with the frame.
  for (double step : {-1.0, 5.0, std::nan("")}) {
    frame.disparity_step_px = step;
    Mapper mapper(noise_mode);
    const IntegrationResult r = mapper.integrate(frame);
    EXPECT_FALSE(r.accepted) << step;
    EXPECT_EQ(r.reason, RejectReason::kInvalidFrame) << step;
    EXPECT_NE(r.error.find("disparity step (DisparityImage.delta_d)"), std::string::npos)
        << r.error;
    EXPECT_EQ(mapper.tsdf().blockCount(), 0u);
  }
}
