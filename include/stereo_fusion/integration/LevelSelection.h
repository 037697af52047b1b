#pragma once
// Where a frame's measurements switch to coarser levels (eq. 3.2): at fixed depths (the thesis),
// or where the stereo depth error reaches the next level's voxel edge.

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/map/ResolutionLevel.h"

namespace stereo_fusion {

/// What level selection reads (from the parameter table: StageConfigs).
struct LevelConfig {
  LevelMode level_mode = MapperConfig{}.level_mode;
  double voxel_size_m = MapperConfig{}.voxel_size_m;
  double disparity_noise_px = MapperConfig{}.disparity_noise_px;
  LevelThresholds levels = MapperConfig{}.levels;  ///< the switch depths of LevelMode::kDepth
};

/// The depth error (1σ, metres) of a measurement at `depth_m` from a camera with f · b =
/// `fb_px_m` whose disparities have an error of `disparity_noise_px` (1σ): σ_z = z² σ_d / (f b)
/// (eq. 3.1 propagated to first order).
inline double depthNoiseM(double depth_m, double fb_px_m, double disparity_noise_px) {
  return depth_m * depth_m * disparity_noise_px / fb_px_m;
}

/// The disparity error (1σ, px) of a source: disparity_noise_px, but never below what quantising
/// disparities to steps of `disparity_step_px` alone costs (step/√12, a uniform rounding error;
/// DisparityImage.delta_d, 0 = unknown). SGBM's 1/16 px steps add nothing (0.018 px); a matcher
/// that gives whole pixels is at least 0.29 px.
double disparityNoisePx(const LevelConfig& config, double disparity_step_px);

/// The switch depths a frame from a camera with f · b = `fb_px_m` uses. kDepth: the configured
/// ones. kNoise: a measurement is fused at the finest level whose voxel edge (voxel_size_m · 2^l)
/// is at least its depth error, so level l starts at z_l = sqrt(2^(l−1) · voxel_size_m · f · b /
/// σ_d) with σ_d = disparityNoisePx(config, disparity_step_px): a precise camera (long
/// baseline, small σ_d) stays fine farther, a noisy one goes coarse sooner.
LevelThresholds levelThresholdsFor(const LevelConfig& config, double fb_px_m,
                                   double disparity_step_px = 0.0);

}  // namespace stereo_fusion
