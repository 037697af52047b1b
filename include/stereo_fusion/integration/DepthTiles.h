#pragma once
#include <cstddef>
#include <vector>

#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// A coarse summary of a frame's depths that lets the fuser prove, for a whole group of
/// finest-level voxels at once, that none of them can be updated (and skip their per-voxel
/// projections).
///
/// The image is cut into kTilePx × kTilePx tiles (the last row and column may be smaller). For
/// each tile it keeps the largest depth among the tile's measurements that may update the
/// finest level (level 0): those of level 0, i.e. below both level switches (levelForDepth(),
/// decided with the kernels' own float thresholds), and, for blocks that already hold level 0
/// (measurementUpdatesLevel()), those of level 0 or 1, i.e. below the level-2 switch; −inf if
/// there is none (all NaN or all coarser). A voxel at depth z_c can only be updated by a
/// surface at depth ≥ z_c − Φ (eq. 3.15), so if every tile under a voxel group's footprint
/// stays below z_min − Φ, the group is untouched. (The same test at level 1 was measured to
/// cost more than it saved, so coarser levels have none.)
class DepthTiles {
 public:
  static constexpr int kTilePx = 8;
  /// Which measurements a summary covers: level 0 only, or levels 0 and 1.
  enum class Measurements { kLevel0, kLevel0And1 };

  /// Summarises `depth_m` (width_px per row, NaN = no measurement) with the float thresholds
  /// of FusionFrame: a depth z may update level 0 iff !(z ≥ level1_min_depth_m) and
  /// !(z ≥ level2_min_depth_m) (the configuration allows the level-2 switch below the level-1 one).
  void build(const float* depth_m, int width_px, int height_px, float level1_min_depth_m,
             float level2_min_depth_m, ThreadPool* pool);

  int tilesX() const { return tiles_x_; }
  int tilesY() const { return tiles_y_; }

  /// Largest depth of `which` measurements among the pixels of tiles [tx0, tx1] × [ty0, ty1]
  /// (inclusive); −inf if none.
  float maxDepth(Measurements which, int tx0, int ty0, int tx1, int ty1) const;

  /// Whether every tile of [tx0, tx1] × [ty0, ty1] has its maxDepth(which) below `limit_m`;
  /// stops at the first that has not.
  bool allBelow(Measurements which, int tx0, int ty0, int tx1, int ty1, float limit_m) const {
    const std::vector<float>& max_depth_m = summary(which);
    for (int ty = ty0; ty <= ty1; ++ty) {
      const float* row = max_depth_m.data() + static_cast<size_t>(ty) * tiles_x_;
      for (int tx = tx0; tx <= tx1; ++tx)
        if (!(row[tx] < limit_m)) return false;
    }
    return true;
  }

 private:
  const std::vector<float>& summary(Measurements which) const {
    return which == Measurements::kLevel0 ? max_level0_depth_m_ : max_level01_depth_m_;
  }

  std::vector<float> max_level0_depth_m_;   ///< tiles_x_ per row
  std::vector<float> max_level01_depth_m_;  ///< tiles_x_ per row
  int tiles_x_ = 0;
  int tiles_y_ = 0;
};

}  // namespace stereo_fusion
