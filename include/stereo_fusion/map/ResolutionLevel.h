#pragma once
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
constexpr int levelVoxelCount(int level) { return levelSide(level) * levelSide(level) * levelSide(level); }

/// Depth thresholds of eq. 3.2. The thesis' s(z) = 2^⌊log2 z⌋ clamped to {1, 2, 4} switches to
/// s = 2 at z = 2 m and to s = 4 at z = 4 m; both switch depths are parameters here.
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

}  // namespace stereo_fusion
