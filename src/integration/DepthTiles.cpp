#include "stereo_fusion/integration/DepthTiles.h"

#include <algorithm>
#include <cmath>

#include "stereo_fusion/util/CpuFeatures.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>

#include "stereo_fusion/util/Avx2Reduce.h"
#define STEREO_FUSION_HAVE_AVX2_TILES 1
#endif

namespace stereo_fusion {
namespace {

/// The two summaries of one tile, read in one pass.
struct TileMaxima {
  float level0_m = -INFINITY;   ///< largest depth below `level0_end_m`
  float level01_m = -INFINITY;  ///< largest depth below `level01_end_m`
};

/// Largest depths of pixel columns [u0, u1) of `rows` rows below `level0_end_m` (for level-0
/// measurements the smaller of the two level switches: a depth is of level 0 iff it is below
/// both) and below `level01_end_m` (levels 0 and 1: the level-2 switch). Comparisons are false
/// for NaN, so pixels without a measurement never count.
TileMaxima tileMaxScalar(const float* depth_m, int width_px, int rows, int u0, int u1,
                         float level0_end_m, float level01_end_m) {
  TileMaxima max;
  for (int r = 0; r < rows; ++r) {
    const float* row = depth_m + static_cast<size_t>(r) * width_px;
    for (int u = u0; u < u1; ++u) {
      if (row[u] < level0_end_m) max.level0_m = std::max(max.level0_m, row[u]);
      if (row[u] < level01_end_m) max.level01_m = std::max(max.level01_m, row[u]);
    }
  }
  return max;
}

#ifdef STEREO_FUSION_HAVE_AVX2_TILES
/// tileMaxScalar() for an 8-pixel-wide tile, one vector per row (kTilePx == 8). max_ps returns
/// its second operand when either is NaN, so NaN depths, and the depths at or beyond a
/// threshold (set to NaN by OR-ing in their all-ones comparison mask), leave the running
/// maximum unchanged without a blend.
__attribute__((target("avx2"))) TileMaxima tileMaxAvx2(const float* depth_m, int width_px, int rows,
                                                       int u0, float level0_end_m,
                                                       float level01_end_m) {
  const __m256 end0 = _mm256_set1_ps(level0_end_m), end01 = _mm256_set1_ps(level01_end_m);
  __m256 max0 = _mm256_set1_ps(-INFINITY), max01 = max0;
  for (int r = 0; r < rows; ++r) {
    const __m256 z = _mm256_loadu_ps(depth_m + static_cast<size_t>(r) * width_px + u0);
    max0 = _mm256_max_ps(_mm256_or_ps(z, _mm256_cmp_ps(z, end0, _CMP_NLT_UQ)),
                         max0);  // z ≥ end, or NaN
    max01 = _mm256_max_ps(_mm256_or_ps(z, _mm256_cmp_ps(z, end01, _CMP_NLT_UQ)), max01);
  }
  return {horizontalMax(max0), horizontalMax(max01)};
}
#endif

}  // namespace

void DepthTiles::build(const float* depth_m, int width_px, int height_px, float level1_min_depth_m,
                       float level2_min_depth_m, ThreadPool* pool) {
  const float level0_end_m = std::min(level1_min_depth_m, level2_min_depth_m);
  const float level01_end_m = level2_min_depth_m;
  static_assert(kTilePx == 8, "one AVX2 vector per tile row");
  tiles_x_ = (width_px + kTilePx - 1) / kTilePx;
  tiles_y_ = (height_px + kTilePx - 1) / kTilePx;
  max_level0_depth_m_.resize(static_cast<size_t>(tiles_x_) * tiles_y_);
  max_level01_depth_m_.resize(max_level0_depth_m_.size());
  bool use_avx2 = false;
#ifdef STEREO_FUSION_HAVE_AVX2_TILES
  use_avx2 = avx2Supported();
#endif
  // A few tile rows per chunk (~24 pixel rows): the depths were just written, mostly in cache.
  pool->parallelFor(static_cast<size_t>(tiles_y_), 3, [&](size_t begin, size_t end) {
    for (size_t ty = begin; ty < end; ++ty) {
      const int v0 = static_cast<int>(ty) * kTilePx;
      const int rows = std::min(kTilePx, height_px - v0);
      const float* band = depth_m + static_cast<size_t>(v0) * width_px;
      float* out0 = max_level0_depth_m_.data() + ty * tiles_x_;
      float* out01 = max_level01_depth_m_.data() + ty * tiles_x_;
      for (int tx = 0; tx < tiles_x_; ++tx) {
        const int u0 = tx * kTilePx, u1 = std::min(u0 + kTilePx, width_px);
        TileMaxima max;
#ifdef STEREO_FUSION_HAVE_AVX2_TILES
        if (use_avx2 && u1 - u0 == kTilePx)
          max = tileMaxAvx2(band, width_px, rows, u0, level0_end_m, level01_end_m);
        else
#endif
          max = tileMaxScalar(band, width_px, rows, u0, u1, level0_end_m, level01_end_m);
        out0[tx] = max.level0_m;
        out01[tx] = max.level01_m;
      }
    }
  });
  (void)use_avx2;
}

float DepthTiles::maxDepth(Measurements which, int tx0, int ty0, int tx1, int ty1) const {
  const std::vector<float>& max_depth_m = summary(which);
  float max_m = -INFINITY;
  for (int ty = ty0; ty <= ty1; ++ty)
    for (int tx = tx0; tx <= tx1; ++tx)
      max_m = std::max(max_m, max_depth_m[static_cast<size_t>(ty) * tiles_x_ + tx]);
  return max_m;
}

}  // namespace stereo_fusion
