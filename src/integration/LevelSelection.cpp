#include "stereo_fusion/integration/LevelSelection.h"

#include <algorithm>
#include <cmath>

namespace stereo_fusion {

double disparityNoisePx(const LevelConfig& config, double disparity_step_px) {
  return std::max(config.disparity_noise_px, disparity_step_px / std::sqrt(12.0));
}

LevelThresholds levelThresholdsFor(const LevelConfig& config, double fb_px_m,
                                   double disparity_step_px) {
  if (config.level_mode == LevelMode::kDepth) return config.levels;
  // σ_z(z) = v · 2^(l−1)  ⇔  z = sqrt(2^(l−1) · v · f · b / σ_d)
  const double per_voxel =
      config.voxel_size_m * fb_px_m / disparityNoisePx(config, disparity_step_px);
  LevelThresholds t;
  t.scale2_min_depth_m = std::sqrt(per_voxel);
  t.scale4_min_depth_m = std::sqrt(2.0 * per_voxel);
  return t;
}

}  // namespace stereo_fusion
