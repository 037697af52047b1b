#pragma once
#include <cmath>

// The three resolution levels of a voxel block (thesis §3.3, eq. 3.2–3.5).

namespace stereo_fusion {

/// Level 0 = 8³ voxels (scale s = 1), level 1 = 4³ (s = 2), level 2 = 2³ (s = 4).
constexpr int kNumLevels = 3;
constexpr int kFinestSide = 8;

/// Voxels per block edge at `level`: B = 8 / s (eq. 3.3).
constexpr int levelSide(int level) { return kFinestSide >> level; }
/// Scale factor s of `level`: the level's voxel edge is s times the finest voxel edge.
constexpr int levelScale(int level) { return 1 << level; }
/// Offset O of `level` in the block's flat voxel array (eq. 3.5): 0, 512, 576.
constexpr int levelOffset(int level) { return level == 0 ? 0 : (level == 1 ? 512 : 576); }
/// Voxel count of `level`: B³.
constexpr int levelVoxelCount(int level) {
  return levelSide(level) * levelSide(level) * levelSide(level);
}

/// Depth thresholds of eq. 3.2. The thesis' s(z) = 2^⌊log2 z⌋ clamped to {1, 2, 4} switches to
/// s = 2 at z = 2 m and to s = 4 at z = 4 m; both switch depths are parameters here.
/// Where a frame's measurements switch to coarser levels (eq. 3.2; integration/LevelSelection.h).
enum class LevelMode {
  kDepth,  ///< the configured switch depths scale2_min_depth_m / scale4_min_depth_m (thesis: 2 m, 4
           ///< m)
  kNoise,  ///< from the camera: where σ_z = z² · σ_d / (f · b) exceeds the voxel edge of a level
};

struct LevelThresholds {
  double scale2_min_depth_m = 2.0;
  double scale4_min_depth_m = 4.0;
};

/// Level of a measurement whose surface depth is `depth_m` (eq. 3.2 with the thresholds above).
inline int levelForDepth(double depth_m, const LevelThresholds& t) {
  if (depth_m >= t.scale4_min_depth_m) return 2;
  if (depth_m >= t.scale2_min_depth_m) return 1;
  return 0;
}

/// Whether a measurement of `measurement_level` updates the voxels of `voxel_level` in a block:
/// its own level and every coarser one (eq. 3.2 and the thesis' multi-level update); with
/// `update_allocated_finer` also the next finer level when the block already holds it
/// (`voxel_level_allocated`: allocated before the frame's visit). With level_mode noise such a
/// measurement's depth error is below two voxels of that finer level (levelThresholdsFor());
/// it keeps its own band there and a quarter of its weight (kFinerLevelWeightScale), so it
/// fills in and refines what nearer views built without allocating anything.
inline bool measurementUpdatesLevel(int measurement_level, int voxel_level,
                                    bool voxel_level_allocated, bool update_allocated_finer) {
  if (voxel_level >= measurement_level) return true;
  return update_allocated_finer && voxel_level_allocated && voxel_level == measurement_level - 1;
}

/// levelForDepth() for float depths, with float compares only: each threshold becomes the
/// smallest float at or above it, so for every float z, z ≥ level1_min_depth_m ⇔
/// (double)z ≥ scale2_min_depth_m (likewise level 2) and levelOf(z) == levelForDepth(z).
/// The lookup and the fusion kernels select a measurement's level with it.
struct FloatLevelThresholds {
  float level1_min_depth_m = 0, level2_min_depth_m = 0;

  FloatLevelThresholds() = default;
  explicit FloatLevelThresholds(const LevelThresholds& t)
      : level1_min_depth_m(smallestFloatAtOrAbove(t.scale2_min_depth_m)),
        level2_min_depth_m(smallestFloatAtOrAbove(t.scale4_min_depth_m)) {}

  /// NaN selects level 0.
  int levelOf(float depth_m) const {
    if (depth_m >= level2_min_depth_m) return 2;
    if (depth_m >= level1_min_depth_m) return 1;
    return 0;
  }

  static float smallestFloatAtOrAbove(double t) {
    float f = static_cast<float>(t);
    if (static_cast<double>(f) < t) f = std::nextafter(f, INFINITY);
    return f;
  }
};

}  // namespace stereo_fusion
