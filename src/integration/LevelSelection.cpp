#include "stereo_fusion/integration/LevelSelection.h"

#include <cmath>

#include "stereo_fusion/MapperConfig.h"

namespace stereo_fusion {

LevelThresholds levelThresholdsFor(const MapperConfig& config, double fb_px_m) {
  if (config.level_mode == LevelMode::kDepth) return config.levels;
  // σ_z(z) = v · 2^(l−1)  ⇔  z = sqrt(2^(l−1) · v · f · b / σ_d)
  const double per_voxel = config.voxel_size_m * fb_px_m / config.disparity_noise_px;
  LevelThresholds t;
  t.scale2_min_depth_m = std::sqrt(per_voxel);
  t.scale4_min_depth_m = std::sqrt(2.0 * per_voxel);
  return t;
}

}  // namespace stereo_fusion
