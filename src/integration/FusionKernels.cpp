#include "stereo_fusion/integration/FusionKernels.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "stereo_fusion/integration/FusionMath.h"
#include "FusionKernelParts.h"
#include "stereo_fusion/integration/SurfaceFuser.h"

#if defined(__x86_64__) || defined(__i386__)
#define STEREO_FUSION_HAVE_AVX2_KERNEL 1  // in FusionKernelsAvx2.cpp
#endif

// No function in this file may be compiled with FMA enabled: GCC (gnu++17) contracts a*b + c
// into one fused operation whenever the target has FMA, which rounds once instead of twice and
// would make the AVX2 kernel disagree with the scalar one. target("avx2") does not enable FMA.

namespace stereo_fusion {
namespace {

/// Eq. 3.8–3.9 for one voxel, with the colour of `pixel` if colour is fused. `sdf_m` is the
/// untruncated distance; it is clamped to −Φ here (observed free space).
inline void updateVoxel(const FusionFrame& f, size_t pixel, float sdf_m, float truncation_m,
                        float weight, Voxel* voxel) {
  uint8_t rgb[3];
  if (f.rgb != nullptr) MeasurementImage::unpack(f.rgb[pixel], rgb);
  const float truncated = std::max(sdf_m, -truncation_m);
  voxel->weight =
      weightBeforeUpdate(voxel->sdf_m, voxel->weight, truncated, truncation_m, f.contradicted_keep);
  fuseMeasurement(voxel, truncated, weight, f.max_weight, f.rgb != nullptr ? rgb : nullptr);
}

}  // namespace

FusionFrame makeFusionFrame(const StereoFrame& frame, const FusionConfig& config,
                            const MeasurementImage& measurements) {
  const StereoCamera& cam = frame.camera;
  FusionFrame f;
  f.T_camera_world = frame.T_world_camera.inverse();
  f.R_cw = f.T_camera_world.linear().cast<float>();
  f.fx_px = static_cast<float>(cam.fx());
  f.fy_px = static_cast<float>(cam.fy());
  f.cx_px = static_cast<float>(cam.cx());
  f.cy_px = static_cast<float>(cam.cy());
  f.width_px = cam.width();
  f.height_px = cam.height();
  f.u_end_px = f.width_px - 0.5f;
  f.v_end_px = f.height_px - 0.5f;
  f.voxel_m = static_cast<float>(config.voxel_size_m);
  const TruncationBand band = config.truncationBand();
  f.max_truncation_m = band.maxM<float>();
  for (int m = 0; m < kNumLevels; ++m) {
    const float scale = static_cast<float>(levelScale(m));
    f.delta_m[m] = static_cast<float>(config.weight_falloff_start_vox) * scale * f.voxel_m;
  }
  for (int level = 0; level < kNumLevels; ++level) {
    FusionFrame::Level& geometry = f.levels[level];
    const float level_voxel_m = f.voxel_m * levelScale(level);
    geometry.ex_m = f.R_cw.col(0) * level_voxel_m;
    geometry.ey_m = f.R_cw.col(1) * level_voxel_m;
    geometry.ez_m = f.R_cw.col(2) * level_voxel_m;
    for (int m = 0; m < kNumLevels; ++m) geometry.truncation_m[m] = band.updateM<float>(m, level);
  }
  f.max_weight = static_cast<float>(config.max_weight);
  f.contradicted_keep =
      config.free_space_carving ? static_cast<float>(1.0 - config.free_space_decay) : 1.0f;
  f.depth_weight_reference_m = static_cast<float>(config.depth_weight_reference_m);
  f.weight_mode = config.weight_mode;
  f.update_allocated_finer = config.update_allocated_finer_level;
  f.thresholds = measurements.levels();
  const FloatLevelThresholds float_thresholds(measurements.levels());
  f.level1_min_depth_m = float_thresholds.level1_min_depth_m;
  f.level2_min_depth_m = float_thresholds.level2_min_depth_m;
  f.depth_m = measurements.depths();
  if (config.use_color && !frame.color.empty()) f.rgb = measurements.colours();
  return f;
}

uint64_t fuseBlockScalar(const FusionFrame& f, const BlockOctree& octree, VoxelBlock* block) {
  const Eigen::Vector3f origin_c = fusion_kernels::blockOriginInCamera(f, octree, block->key);
  uint64_t updates = 0;
  for (int level = fusion_kernels::firstLevelToVisit(f, origin_c, *block); level < kNumLevels;
       ++level) {
    const FusionFrame::Level& geometry = f.levels[level];
    const int side = levelSide(level);
    const Eigen::Vector3f first = origin_c + 0.5f * (geometry.ex_m + geometry.ey_m + geometry.ez_m);
    const bool allocated = block->hasLevel(level);  // before this visit
    fusion_kernels::LevelTarget target(block, level);
    Voxel* voxels = target.voxels();
    uint64_t level_updates = 0;
    for (int k = 0; k < side; ++k) {
      for (int j = 0; j < side; ++j) {
        for (int i = 0; i < side; ++i) {
          const Eigen::Vector3f p = first + static_cast<float>(i) * geometry.ex_m +
                                    static_cast<float>(j) * geometry.ey_m +
                                    static_cast<float>(k) * geometry.ez_m;
          size_t pixel;
          if (!nearestPixel(f, p, &pixel)) continue;
          const float surface_depth = f.depth_m[pixel];
          if (std::isnan(surface_depth)) continue;  // no usable measurement
          const int measurement_level = levelForDepth(surface_depth, f.thresholds);
          if (!measurementUpdatesLevel(measurement_level, level, allocated,
                                       f.update_allocated_finer))
            continue;  // too fine for this measurement
          const float truncation = geometry.truncation_m[measurement_level];
          const float delta = f.delta_m[measurement_level];
          const float sdf = signedDistanceAlongRay(p.x(), p.y(), p.z(), surface_depth);
          if (sdf > truncation) continue;  // far behind the surface: unobserved
          const float w = measurementWeight(f.weight_mode, sdf, delta, truncation, surface_depth,
                                            f.depth_weight_reference_m) *
                          (level < measurement_level ? kFinerLevelWeightScale : 1.0f);
          if (!(w > 0.0f)) continue;
          updateVoxel(f, pixel, sdf, truncation, w, &voxels[i + j * side + k * side * side]);
          ++level_updates;
        }
      }
    }
    updates += target.commit(level_updates);
  }
  return updates;
}

#ifndef STEREO_FUSION_HAVE_AVX2_KERNEL  // not x86: only the scalar kernel

uint64_t fuseBlockAvx2(const FusionFrame& f, const BlockOctree& octree, VoxelBlock* block) {
  return fuseBlockScalar(f, octree, block);
}

#endif

}  // namespace stereo_fusion
