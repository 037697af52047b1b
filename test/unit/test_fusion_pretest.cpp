// DepthTiles against a per-pixel transcription of their rule.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "stereo_fusion/integration/DepthTiles.h"

namespace stereo_fusion {
namespace {

/// The largest depth among pixels [u0, u1) × [v0, v1) whose measurement level is ≤ `level`
/// (levelForDepth() with float thresholds); −inf if none.
float bruteForceMax(const std::vector<float>& depth_m, int width, int u0, int v0, int u1, int v1, int level,
                    float t1, float t2) {
  float max_m = -std::numeric_limits<float>::infinity();
  for (int v = v0; v < v1; ++v)
    for (int u = u0; u < u1; ++u) {
      const float z = depth_m[static_cast<size_t>(v) * width + u];
      if (std::isnan(z)) continue;
      const int m = z >= t2 ? 2 : (z >= t1 ? 1 : 0);
      if (m <= level) max_m = std::max(max_m, z);
    }
  return max_m;
}

TEST(DepthTiles, MaxUpdatingDepthFollowsThePerPixelRule) {
  // Sizes that are no multiple of the tile, depths on and around the thresholds, NaN, and a
  // level-2 threshold below the level-1 one (allowed by the configuration).
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  ThreadPool pool(2);
  const int sizes[][2] = {{640, 480}, {13, 9}, {1, 1}, {17, 8}, {8, 17}, {203, 77}};
  for (const auto& size : sizes) {
    for (int variant = 0; variant < 2; ++variant) {
      const int width = size[0], height = size[1];
      const float t1 = 2.0f, t2 = variant == 0 ? 4.0f : 1.5f;
      const float special[] = {t1, std::nextafter(t1, 0.0f), t2, std::nextafter(t2, 0.0f),
                               std::numeric_limits<float>::quiet_NaN(), 0.1f, 7.9f};
      std::vector<float> depth_m(static_cast<size_t>(width) * height);
      for (float& z : depth_m) z = unit(rng) < 0.3f ? special[rng() % std::size(special)] : 0.1f + 6.0f * unit(rng);
      // Whole tiles without a measurement, and tiles with only coarse ones.
      if (width >= 16 && height >= 16)
        for (int v = 0; v < 8; ++v)
          for (int u = 0; u < 8; ++u) {
            depth_m[static_cast<size_t>(v) * width + u] = std::numeric_limits<float>::quiet_NaN();
            depth_m[static_cast<size_t>(v) * width + 8 + u] = 5.0f;
          }
      DepthTiles tiles;
      tiles.build(depth_m.data(), width, height, t1, t2, &pool);
      ASSERT_EQ(tiles.tilesX(), (width + 7) / 8);
      ASSERT_EQ(tiles.tilesY(), (height + 7) / 8);
      for (int level = 0; level < kNumLevels; ++level)
        for (int ty = 0; ty < tiles.tilesY(); ++ty)
          for (int tx = 0; tx < tiles.tilesX(); ++tx) {
            const float want = bruteForceMax(depth_m, width, 8 * tx, 8 * ty, std::min(8 * tx + 8, width),
                                             std::min(8 * ty + 8, height), level, t1, t2);
            ASSERT_EQ(tiles.maxUpdatingDepth(level, tx, ty, tx, ty), want)
                << width << "x" << height << " level " << level << " tile " << tx << "," << ty;
            EXPECT_EQ(tiles.allBelow(level, tx, ty, tx, ty, std::nextafter(want, INFINITY)), true);
            EXPECT_EQ(tiles.allBelow(level, tx, ty, tx, ty, want), false);
          }
      // A query over several tiles is the maximum over their pixels.
      const float want = bruteForceMax(depth_m, width, 0, 0, width, height, 1, t1, t2);
      EXPECT_EQ(tiles.maxUpdatingDepth(1, 0, 0, tiles.tilesX() - 1, tiles.tilesY() - 1), want);
    }
  }
}

}  // namespace
}  // namespace stereo_fusion
