#pragma once
// The per-voxel equations of surface fusion (thesis §3.5), kept as small inline functions so
// each can be tested with hand-worked numbers and used unchanged in the hot loop.

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/map/Voxel.h"

namespace stereo_fusion {

/// Eq. 3.15: d = ‖x_c‖ · (1 − z / z_c) for a voxel at camera point x_c (depth z_c) whose pixel
/// sees the surface at depth z. Negative in front of the surface (free space), positive behind;
/// |d| is the distance along the viewing ray between voxel and surface.
inline float signedDistanceAlongRay(float x_c, float y_c, float z_c, float surface_depth_m) {
  return std::sqrt(x_c * x_c + y_c * y_c + z_c * z_c) * (1.0f - surface_depth_m / z_c);
}

/// Eq. 3.10 with the fall-off on the unobserved side (behind the surface, d > 0):
/// w = 1 for d < δ; (Φ − d)/(Φ − δ) for δ ≤ d ≤ Φ; 0 for d > Φ.
inline float steinbrueckerWeight(float sdf_m, float delta_m, float truncation_m) {
  if (sdf_m < delta_m) return 1.0f;
  if (sdf_m > truncation_m) return 0.0f;
  return (truncation_m - sdf_m) / (truncation_m - delta_m);
}

/// The weight of one measurement of a voxel. `surface_depth_m` is z of eq. 3.15.
inline float measurementWeight(WeightMode mode, float sdf_m, float delta_m, float truncation_m,
                               float surface_depth_m, float reference_depth_m) {
  switch (mode) {
    case WeightMode::kConstant: return sdf_m > truncation_m ? 0.0f : 1.0f;
    case WeightMode::kSteinbruecker: return steinbrueckerWeight(sdf_m, delta_m, truncation_m);
    case WeightMode::kDepthAware: {
      // Stereo depth error grows as z² (eq. 3.1): weight by the inverse, 1 at z_ref.
      const float ratio = reference_depth_m / surface_depth_m;
      return steinbrueckerWeight(sdf_m, delta_m, truncation_m) * ratio * ratio;
    }
  }
  return 0.0f;
}

/// Factor on the weight of a measurement that updates a level finer than its own
/// (measurementUpdatesLevel()). Its depth error is up to twice that of the level's own
/// measurements (levelThresholdsFor(): the level switches where σ_z doubles), so inverse-variance
/// weighting gives it a quarter: it fills what nearer views left unobserved and moves what they
/// observed only a little. A power of two, so the product is exact in either kernel.
constexpr float kFinerLevelWeightScale = 0.25f;

/// The weight W a voxel brings into eq. 3.8 when a measurement contradicts it by more than the
/// band, |D − d| > Φ (d already truncated to [−Φ, Φ]): the world changed there — an object left
/// or arrived — or one of the two is an outlier. It keeps `keep` (1 − free_space_decay) of
/// itself, so a change wins within a few frames rather than after as many frames as W counts;
/// otherwise W. keep = 1 is the thesis' plain running average.
inline float weightBeforeUpdate(float stored_sdf_m, float stored_weight, float truncated_sdf_m,
                                float truncation_m, float keep) {
  return std::abs(stored_sdf_m - truncated_sdf_m) > truncation_m ? stored_weight * keep
                                                                 : stored_weight;
}

/// Eq. 3.8–3.9: D ← (W·D + w·d)/(W + w), W ← min(W + w, W_max); colour averaged with the same
/// weights. `sdf_m` must already be truncated to [−Φ, Φ].
inline void fuseMeasurement(Voxel* voxel, float sdf_m, float weight, float max_weight,
                            const uint8_t* rgb) {
  const float w_old = voxel->weight;
  const float w_sum = w_old + weight;
  voxel->sdf_m = (w_old * voxel->sdf_m + weight * sdf_m) / w_sum;
  if (rgb != nullptr) {
    auto blend = [&](uint8_t old_c, uint8_t new_c) {
      const float c = (w_old * old_c + weight * new_c) / w_sum;
      return static_cast<uint8_t>(std::clamp(c + 0.5f, 0.0f, 255.0f));
    };
    voxel->r = blend(voxel->r, rgb[0]);
    voxel->g = blend(voxel->g, rgb[1]);
    voxel->b = blend(voxel->b, rgb[2]);
  }
  voxel->weight = std::min(w_sum, max_weight);
}

}  // namespace stereo_fusion
