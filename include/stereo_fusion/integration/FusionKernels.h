#pragma once
// The per-block voxel loops of SurfaceFuser: one portable scalar kernel and one AVX2 kernel
// that visits eight voxels at a time. Both perform the float operations of eq. 3.11–3.15 in
// the same order (SSE/AVX add, mul, div and sqrt are correctly rounded, and neither kernel
// may contract mul+add into FMA), so their results are bit-identical; the tests hold them
// against each other and against a per-voxel transcription of the equations.

#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/integration/DepthTiles.h"
#include "stereo_fusion/integration/MeasurementImage.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/map/VoxelBlock.h"
#include "stereo_fusion/util/CpuFeatures.h"

namespace stereo_fusion {

/// What the kernels need from one frame and the configuration, derived once per frame and
/// shared read-only by all blocks (and threads).
/// What SurfaceFuser (stage 2) reads (from the parameter table: StageConfigs): the voxel kernels
/// apply (makeFusionFrame()): voxel geometry, bands, weights (eq. 3.8–3.10), the finer-level rule,
/// contradiction decay and colour.
struct FusionConfig {
  double voxel_size_m = MapperConfig{}.voxel_size_m;
  double truncation_vox = MapperConfig{}.truncation_vox;
  WeightMode weight_mode = MapperConfig{}.weight_mode;
  double weight_falloff_start_vox = MapperConfig{}.weight_falloff_start_vox;
  double depth_weight_reference_m = MapperConfig{}.depth_weight_reference_m;
  double max_weight = MapperConfig{}.max_weight;
  bool update_allocated_finer_level = MapperConfig{}.update_allocated_finer_level;
  /// With free_space_carving, a contradicted voxel keeps 1 − free_space_decay of its weight.
  bool free_space_carving = MapperConfig{}.free_space_carving;
  double free_space_decay = MapperConfig{}.free_space_decay;
  bool use_color = MapperConfig{}.use_color;

  /// Φ by level, as MapperConfig::truncationBand() gives it.
  TruncationBand truncationBand() const { return TruncationBand(voxel_size_m, truncation_vox); }
};

struct FusionFrame {
  /// Per voxel level: the steps between neighbouring voxel centres in camera coordinates and
  /// the band half-width Φ for a measurement of each level (eq. 3.15, never below
  /// 2 of this level's voxels, TruncationBand::updateM()).
  struct Level {
    Eigen::Vector3f ex_m, ey_m, ez_m;
    float truncation_m[kNumLevels];  ///< indexed by the measurement's level
  };

  Eigen::Isometry3d T_camera_world;
  Eigen::Matrix3f R_cw;
  float fx_px = 0, fy_px = 0, cx_px = 0, cy_px = 0;
  int width_px = 0, height_px = 0;
  /// width − 0.5, height − 0.5: projections at or beyond round to a pixel outside the image.
  float u_end_px = 0, v_end_px = 0;
  float voxel_m = 0;
  /// Half-width of the widest band of any level: bounds how far in front of its surface a
  /// voxel can be updated (block-level level skipping).
  float max_truncation_m = 0;
  float delta_m[kNumLevels] = {};  ///< δ of eq. 3.10 by measurement level
  float max_weight = 0;
  /// What a contradicted voxel keeps of its weight (weightBeforeUpdate()): 1 − free_space_decay
  /// with free_space_carving, else 1.
  float contradicted_keep = 1.0f;
  float depth_weight_reference_m = 0;
  WeightMode weight_mode = WeightMode::kSteinbruecker;
  LevelThresholds thresholds;
  /// MapperConfig::update_allocated_finer_level: a measurement also updates the next finer
  /// level of a block that already holds it (measurementUpdatesLevel()).
  bool update_allocated_finer = false;
  /// FloatLevelThresholds of `thresholds`: a float comparison decides levelForDepth() exactly.
  float level1_min_depth_m = 0, level2_min_depth_m = 0;
  Level levels[kNumLevels];
  const float* depth_m = nullptr;  ///< MeasurementImage::depths(), width_px per row
  /// MeasurementImage::colours(); nullptr: colour is not fused.
  const uint32_t* rgb = nullptr;
  /// Tile summary of depth_m built with level1/level2_min_depth_m; lets the AVX2 kernel skip
  /// groups of voxels that provably get no update. nullptr: every voxel is visited.
  const DepthTiles* tiles = nullptr;
};

/// Eq. 3.12–3.14: the nearest pixel of camera point `p_c`, as an index into the frame's images;
/// false when it lies behind the camera or projects outside the image. Bounds are checked in
/// float first: u, v can be huge or infinite for z_c near 0. (The scalar kernel's rule; the
/// AVX2 kernel repeats it eight lanes at a time.)
inline bool nearestPixel(const FusionFrame& f, const Eigen::Vector3f& p_c, size_t* pixel) {
  if (!(p_c.z() > 0.0f)) return false;
  const float u = f.fx_px * p_c.x() / p_c.z() + f.cx_px;
  const float v = f.fy_px * p_c.y() / p_c.z() + f.cy_px;
  if (!(u >= -0.5f && v >= -0.5f && u < f.u_end_px && v < f.v_end_px)) return false;
  const int iu = static_cast<int>(std::floor(u + 0.5f));
  const int iv = static_cast<int>(std::floor(v + 0.5f));
  if (iu < 0 || iv < 0 || iu >= f.width_px || iv >= f.height_px) return false;
  *pixel = static_cast<size_t>(iv) * f.width_px + iu;
  return true;
}

/// Derives the FusionFrame of `frame`; `measurements` must already hold the frame's depths and,
/// if colour is fused, its colours.
FusionFrame makeFusionFrame(const StereoFrame& frame, const FusionConfig& config,
                            const MeasurementImage& measurements);

/// Fuses `frame` into every voxel of `block` that it observes; returns the number of voxel
/// updates. Portable reference path.
uint64_t fuseBlockScalar(const FusionFrame& frame, const BlockOctree& octree, VoxelBlock* block);

/// Same result as fuseBlockScalar(), bit for bit, eight voxels per step. Only call it when
/// avx2Supported().
uint64_t fuseBlockAvx2(const FusionFrame& frame, const BlockOctree& octree, VoxelBlock* block);

}  // namespace stereo_fusion
