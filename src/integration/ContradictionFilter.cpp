#include "stereo_fusion/integration/ContradictionFilter.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "stereo_fusion/map/ResolutionLevel.h"

namespace stereo_fusion {

namespace {

constexpr int kTile = ContradictionFilter::kTilePx;

/// The confident surfaces `block` shows the camera, splatted into `tile_far_m`: every tile a
/// voxel's footprint covers keeps the farthest such surface depth.
void splatBlock(const VoxelBlock& block, const BlockOctree& octree, const StereoCamera& camera,
                const Eigen::Isometry3d& T_camera_world, double block_m, float min_weight,
                int tiles_x, int tiles_y, float* tile_far_m) {
  const int level = block.hasLevel(1) ? 1 : (block.hasLevel(2) ? 2 : -1);
  if (level < 0) return;
  const int side = levelSide(level);
  const double voxel_m = block_m / side;
  const Eigen::Vector3d origin = octree.blockOrigin(block.key);
  const Voxel* voxels = block.level(level);
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) {
        const Voxel& v = voxels[i + side * (j + side * k)];
        if (!(v.weight >= min_weight) || !(std::abs(v.sdf_m) <= voxel_m)) continue;
        const Eigen::Vector3d p_c =
            T_camera_world * (origin + voxel_m * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5));
        Eigen::Vector2d uv;
        if (!camera.project(p_c, &uv) || !camera.isInImage(uv)) continue;
        // sdf > 0 behind the surface, measured along the ray: the surface lies that much nearer.
        const float far_m = static_cast<float>(p_c.z() - v.sdf_m * p_c.z() / p_c.norm() + voxel_m);
        if (!std::isfinite(far_m)) continue;  // no surface to keep (std::max would skip a NaN too)
        // At most the image: a voxel at the camera covers it, and the tile loops stay in int.
        const double r = std::min(0.5 * camera.fx() * voxel_m / p_c.z(),
                                  static_cast<double>(camera.width() + camera.height()));
        auto tileOf = [](double px, int tiles) {
          return std::clamp(static_cast<int>(std::floor(px + 0.5)) / kTile, 0, tiles - 1);
        };
        for (int ty = tileOf(uv.y() - r, tiles_y); ty <= tileOf(uv.y() + r, tiles_y); ++ty)
          for (int tx = tileOf(uv.x() - r, tiles_x); tx <= tileOf(uv.x() + r, tiles_x); ++tx)
            tile_far_m[ty * tiles_x + tx] = std::max(tile_far_m[ty * tiles_x + tx], far_m);
      }
}

float median(std::vector<float>* values) {
  std::nth_element(values->begin(), values->begin() + values->size() / 2, values->end());
  return (*values)[values->size() / 2];
}

}  // namespace

ContradictionStats ContradictionFilter::apply(const StereoFrame& frame, const BlockOctree& octree,
                                              const std::vector<VoxelBlock*>& blocks,
                                              const ContradictionConfig& config, double sigma_d_px,
                                              ThreadPool* pool, MeasurementImage* measurements) {
  ContradictionStats stats;
  const StereoCamera& camera = frame.camera;
  const int width = measurements->width(), height = measurements->height();
  const int tiles_x = (width + kTile - 1) / kTile, tiles_y = (height + kTile - 1) / kTile;
  const size_t tiles = static_cast<size_t>(tiles_x) * tiles_y;
  const float* depth = measurements->depths();
  const double fb = camera.fx() * camera.baseline();
  const double sigma_d = sigma_d_px;
  auto margin = [&](double z) { return config.contradiction_sigmas * z * z * sigma_d / fb; };

  // 1. Confident surfaces: each share of the blocks splatted into tiles of its own, in
  // parallel, then the shares' maxima. A maximum is exact in any order: thread-count independent.
  const Eigen::Isometry3d T_camera_world = frame.T_world_camera.inverse();
  const double block_m = config.voxel_size_m * kFinestSide;
  const auto min_weight = static_cast<float>(config.contradiction_min_weight);
  const size_t shares = std::min(blocks.size(), static_cast<size_t>(4 * pool->size()));
  share_far_m_.assign(shares * tiles, -1.0f);
  pool->parallelFor(shares, 1, [&](size_t begin, size_t end) {
    for (size_t share = begin; share < end; ++share)
      for (size_t b = share * blocks.size() / shares; b < (share + 1) * blocks.size() / shares; ++b)
        splatBlock(*blocks[b], octree, camera, T_camera_world, block_m, min_weight, tiles_x,
                   tiles_y, share_far_m_.data() + share * tiles);
  });
  tile_far_m_.assign(tiles, -1.0f);
  pool->parallelFor(tiles, 1024, [&](size_t begin, size_t end) {
    for (size_t share = 0; share < shares; ++share) {
      const float* far_m = share_far_m_.data() + share * tiles;
      for (size_t t = begin; t < end; ++t) tile_far_m_[t] = std::max(tile_far_m_[t], far_m[t]);
    }
  });

  // 2. Trust: the median measured depth of each tile (over its pixels at even rows and
  // columns: a quarter of the work, as robust), then of its 3×3 tiles.
  tile_median_m_.assign(tiles, std::numeric_limits<float>::quiet_NaN());
  pool->parallelFor(static_cast<size_t>(tiles_y), 4, [&](size_t begin, size_t end) {
    std::vector<float> values;
    for (size_t ty = begin; ty < end; ++ty)
      for (int tx = 0; tx < tiles_x; ++tx) {
        values.clear();
        for (int v = static_cast<int>(ty) * kTile;
             v < std::min(height, (static_cast<int>(ty) + 1) * kTile); v += 2)
          for (int u = tx * kTile; u < std::min(width, (tx + 1) * kTile); u += 2)
            if (!std::isnan(depth[v * width + u])) values.push_back(depth[v * width + u]);
        if (!values.empty()) tile_median_m_[ty * tiles_x + tx] = median(&values);
      }
  });
  std::vector<float> trusted(tiles, -1.0f);
  pool->parallelFor(static_cast<size_t>(tiles_y), 4, [&](size_t begin, size_t end) {
    std::vector<float> around;
    for (int ty = static_cast<int>(begin); ty < static_cast<int>(end); ++ty)
      for (int tx = 0; tx < tiles_x; ++tx) {
        const float far_m = tile_far_m_[ty * tiles_x + tx];
        if (far_m < 0.0f) continue;
        around.clear();
        for (int y = std::max(0, ty - 1); y <= std::min(tiles_y - 1, ty + 1); ++y)
          for (int x = std::max(0, tx - 1); x <= std::min(tiles_x - 1, tx + 1); ++x)
            if (!std::isnan(tile_median_m_[y * tiles_x + x]))
              around.push_back(tile_median_m_[y * tiles_x + x]);
        if (around.empty()) continue;
        const float m = median(&around);
        if (m <= far_m + margin(m)) trusted[ty * tiles_x + tx] = far_m;
      }
  });
  stats.tiles_with_surface = static_cast<uint64_t>(
      std::count_if(trusted.begin(), trusted.end(), [](float far_m) { return far_m >= 0.0f; }));

  // 3. Behind, per tile row in parallel (a row of tiles owns its pixels and counters).
  tile_valid_.assign(tiles, 0);
  tile_behind_.assign(tiles, 0);
  reject_.create(height, width, CV_8UC1);
  reject_.setTo(0);
  pool->parallelFor(static_cast<size_t>(tiles_y), 4, [&](size_t begin, size_t end) {
    for (int v = static_cast<int>(begin) * kTile;
         v < std::min(height, static_cast<int>(end) * kTile); ++v)
      for (int u = 0; u < width; ++u) {
        const float z = depth[v * width + u];
        if (std::isnan(z)) continue;
        const size_t t = static_cast<size_t>(v / kTile) * tiles_x + u / kTile;
        ++tile_valid_[t];
        // Behind the tile's confident surface, trusted or not: what the share counts. Only a
        // trusted one may drop it.
        if (tile_far_m_[t] >= 0.0f && z > tile_far_m_[t] + margin(z)) {
          ++tile_behind_[t];
          if (trusted[t] >= 0.0f) reject_.at<uint8_t>(v, u) = 1;
        }
      }
  });

  // 4. Isolated: few of the measurements around are behind as well.
  std::vector<uint8_t> isolated(tiles, 0);
  const int w = kShareWindowTiles;
  pool->parallelFor(static_cast<size_t>(tiles_y), 4, [&](size_t begin, size_t end) {
    for (int ty = static_cast<int>(begin); ty < static_cast<int>(end); ++ty)
      for (int tx = 0; tx < tiles_x; ++tx) {
        uint64_t valid = 0, behind = 0;
        for (int y = std::max(0, ty - w); y <= std::min(tiles_y - 1, ty + w); ++y)
          for (int x = std::max(0, tx - w); x <= std::min(tiles_x - 1, tx + w); ++x) {
            valid += tile_valid_[y * tiles_x + x];
            behind += tile_behind_[y * tiles_x + x];
          }
        isolated[ty * tiles_x + tx] = static_cast<double>(behind) <=
                                      config.contradiction_max_share * static_cast<double>(valid);
      }
    // Then the rejections of these tile rows that are not isolated are withdrawn.
    for (int v = static_cast<int>(begin) * kTile;
         v < std::min(height, static_cast<int>(end) * kTile); ++v) {
      uint8_t* row = reject_.ptr<uint8_t>(v);
      for (int u = 0; u < width; ++u)
        if (row[u] && !isolated[static_cast<size_t>(v / kTile) * tiles_x + u / kTile]) row[u] = 0;
    }
  });
  for (uint32_t behind : tile_behind_) stats.pixels_behind += behind;
  stats.pixels_rejected = measurements->invalidate(reject_, pool);
  return stats;
}

}  // namespace stereo_fusion
