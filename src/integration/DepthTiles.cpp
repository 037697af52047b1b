#include "stereo_fusion/integration/DepthTiles.h"

#include <algorithm>
#include <cmath>

#include "stereo_fusion/util/CpuFeatures.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define STEREO_FUSION_HAVE_AVX2_TILES 1
#endif

namespace stereo_fusion {
namespace {

/// Largest depths of pixel columns [u0, u1) of `rows` rows that may update each voxel level.
/// Comparisons are false for NaN, so pixels without a measurement never count.
void tileMaxScalar(const float* depth_m, int width_px, int rows, int u0, int u1, float level1_min_depth_m,
                   float level2_min_depth_m, float out_m[kNumLevels]) {
  for (int level = 0; level < kNumLevels; ++level) out_m[level] = -INFINITY;
  for (int r = 0; r < rows; ++r) {
    const float* row = depth_m + static_cast<size_t>(r) * width_px;
    for (int u = u0; u < u1; ++u) {
      const float z = row[u];
      if (std::isnan(z)) continue;
      const bool reaches1 = z >= level1_min_depth_m, reaches2 = z >= level2_min_depth_m;
      if (!reaches1 && !reaches2) out_m[0] = std::max(out_m[0], z);
      if (!reaches2) out_m[1] = std::max(out_m[1], z);
      out_m[2] = std::max(out_m[2], z);
    }
  }
}

#ifdef STEREO_FUSION_HAVE_AVX2_TILES
__attribute__((target("avx2"))) float horizontalMax(__m256 v) {
  __m128 m = _mm_max_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  m = _mm_max_ps(m, _mm_movehl_ps(m, m));
  m = _mm_max_ss(m, _mm_shuffle_ps(m, m, 1));
  return _mm_cvtss_f32(m);
}

/// tileMaxScalar() for an 8-pixel-wide tile, one vector per row (kTilePx == 8). max_ps returns
/// its second operand when either is NaN, so NaN depths, and the depths of measurements too
/// coarse for a level (set to NaN by OR-ing in their all-ones comparison mask), leave the
/// running maxima unchanged without a blend.
__attribute__((target("avx2"))) void tileMaxAvx2(const float* depth_m, int width_px, int rows, int u0,
                                                 float level1_min_depth_m, float level2_min_depth_m,
                                                 float out_m[kNumLevels]) {
  const __m256 t1 = _mm256_set1_ps(level1_min_depth_m), t2 = _mm256_set1_ps(level2_min_depth_m);
  __m256 max0 = _mm256_set1_ps(-INFINITY), max1 = max0, max2 = max0;
  for (int r = 0; r < rows; ++r) {
    const __m256 z = _mm256_loadu_ps(depth_m + static_cast<size_t>(r) * width_px + u0);
    const __m256 reaches2 = _mm256_cmp_ps(z, t2, _CMP_GE_OQ);
    const __m256 coarser_than_0 = _mm256_or_ps(_mm256_cmp_ps(z, t1, _CMP_GE_OQ), reaches2);
    max2 = _mm256_max_ps(z, max2);
    max1 = _mm256_max_ps(_mm256_or_ps(z, reaches2), max1);
    max0 = _mm256_max_ps(_mm256_or_ps(z, coarser_than_0), max0);
  }
  out_m[0] = horizontalMax(max0);
  out_m[1] = horizontalMax(max1);
  out_m[2] = horizontalMax(max2);
}
#endif

}  // namespace

void DepthTiles::build(const float* depth_m, int width_px, int height_px, float level1_min_depth_m,
                       float level2_min_depth_m, ThreadPool* pool) {
  static_assert(kNumLevels == 3 && kTilePx == 8, "one AVX2 vector per tile row, three levels");
  tiles_x_ = (width_px + kTilePx - 1) / kTilePx;
  tiles_y_ = (height_px + kTilePx - 1) / kTilePx;
  for (auto& tiles : max_depth_m_) tiles.resize(static_cast<size_t>(tiles_x_) * tiles_y_);
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
      for (int tx = 0; tx < tiles_x_; ++tx) {
        const int u0 = tx * kTilePx, u1 = std::min(u0 + kTilePx, width_px);
        float max_m[kNumLevels];
#ifdef STEREO_FUSION_HAVE_AVX2_TILES
        if (use_avx2 && u1 - u0 == kTilePx)
          tileMaxAvx2(band, width_px, rows, u0, level1_min_depth_m, level2_min_depth_m, max_m);
        else
#endif
          tileMaxScalar(band, width_px, rows, u0, u1, level1_min_depth_m, level2_min_depth_m, max_m);
        const size_t tile = ty * tiles_x_ + tx;
        for (int level = 0; level < kNumLevels; ++level) max_depth_m_[level][tile] = max_m[level];
      }
    }
  });
  (void)use_avx2;
}

float DepthTiles::maxUpdatingDepth(int level, int tx0, int ty0, int tx1, int ty1) const {
  float max_m = -INFINITY;
  for (int ty = ty0; ty <= ty1; ++ty)
    for (int tx = tx0; tx <= tx1; ++tx)
      max_m = std::max(max_m, max_depth_m_[level][static_cast<size_t>(ty) * tiles_x_ + tx]);
  return max_m;
}

}  // namespace stereo_fusion
