#include "stereo_fusion/planning/FreeSpaceRecorder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace stereo_fusion {

namespace {

constexpr int kTilePx = 8;
/// Edge of the octree's roots in cells: 4³ planning blocks.
constexpr int kRootCells = 32;
constexpr int kRootBlocks = kRootCells / PlanningBlock::kSide;

struct RootOutput {
  std::array<PlanningBlock::Bits, kRootBlocks * kRootBlocks * kRootBlocks> blocks{};
  FreeSpaceStats stats;
  bool any = false;
};

}  // namespace

void FreeSpaceRecorder::buildTiles(const MeasurementImage& measurements) {
  const int width = measurements.width(), height = measurements.height();
  const float unmeasured = static_cast<float>(params_.unmeasured_range_m);
  const LevelThresholds& levels = measurements.levels();
  float band_m[kNumLevels];
  for (int l = 0; l < kNumLevels; ++l) band_m[l] = params_.band.measurementM<float>(l);

  pyramid_.resize(1);
  TileLevel& base = pyramid_[0];
  base.tile_px = kTilePx;
  base.tiles_x = (width + kTilePx - 1) / kTilePx;
  base.tiles_y = (height + kTilePx - 1) / kTilePx;
  base.min_free_m.assign(static_cast<size_t>(base.tiles_x) * base.tiles_y, 0.0f);
  base.max_free_m.assign(base.min_free_m.size(), 0.0f);
  const float* depth = measurements.depths();
  pool_->parallelFor(static_cast<size_t>(base.tiles_y), 4, [&](size_t begin, size_t end) {
    for (size_t ty = begin; ty < end; ++ty)
      for (int tx = 0; tx < base.tiles_x; ++tx) {
        float lo = std::numeric_limits<float>::infinity(), hi = 0.0f;
        bool said = false, unmeasured_pixel = false;
        for (int v = static_cast<int>(ty) * kTilePx; v < std::min(static_cast<int>(ty + 1) * kTilePx, height); ++v)
          for (int u = tx * kTilePx; u < std::min((tx + 1) * kTilePx, width); ++u) {
            const float z = depth[static_cast<size_t>(v) * width + u];
            if (!(z > 0.0f)) {
              unmeasured_pixel = true;
              continue;
            }
            const float free_m = z - band_m[levelForDepth(z, levels)];
            lo = std::min(lo, free_m);
            hi = std::max(hi, free_m);
            said = true;
          }
        if (unmeasured_pixel && unmeasured > 0.0f) {
          lo = std::min(lo, unmeasured);
          hi = std::max(hi, unmeasured);
          said = true;
        }
        const size_t t = ty * base.tiles_x + tx;
        base.min_free_m[t] = said ? std::max(lo, 0.0f) : 0.0f;
        base.max_free_m[t] = said ? std::max(hi, 0.0f) : 0.0f;
      }
  });
  // Coarser levels: min and max over 2×2 children, until one tile is left.
  while (pyramid_.back().tiles_x > 1 || pyramid_.back().tiles_y > 1) {
    const TileLevel& fine = pyramid_.back();
    TileLevel coarse;
    coarse.tile_px = fine.tile_px * 2;
    coarse.tiles_x = (fine.tiles_x + 1) / 2;
    coarse.tiles_y = (fine.tiles_y + 1) / 2;
    coarse.min_free_m.assign(static_cast<size_t>(coarse.tiles_x) * coarse.tiles_y,
                             std::numeric_limits<float>::infinity());
    coarse.max_free_m.assign(coarse.min_free_m.size(), 0.0f);
    for (int y = 0; y < fine.tiles_y; ++y)
      for (int x = 0; x < fine.tiles_x; ++x) {
        const size_t f = static_cast<size_t>(y) * fine.tiles_x + x;
        const size_t c = static_cast<size_t>(y / 2) * coarse.tiles_x + x / 2;
        coarse.min_free_m[c] = std::min(coarse.min_free_m[c], fine.min_free_m[f]);
        coarse.max_free_m[c] = std::max(coarse.max_free_m[c], fine.max_free_m[f]);
      }
    pyramid_.push_back(std::move(coarse));
  }
}

FreeSpaceStats FreeSpaceRecorder::record(const StereoFrame& frame, const MeasurementImage& measurements,
                                         std::vector<std::pair<BlockKey, PlanningBlock::Bits>>* seen_free) {
  seen_free->clear();
  FreeSpaceStats stats;
  if (measurements.width() <= 0 || measurements.height() <= 0) return stats;
  buildTiles(measurements);
  const double far_m = pyramid_.back().max_free_m[0];
  if (!(far_m > 0.0)) return stats;

  const StereoCamera& camera = frame.camera;
  const double fx = camera.fx(), fy = camera.fy(), cx = camera.cx(), cy = camera.cy();
  const int width = measurements.width(), height = measurements.height();
  const Eigen::Isometry3d T_camera_world = frame.T_world_camera.inverse();
  const double cell_m = params_.cell_m;

  // The frustum's bounding box up to the farthest free depth → root nodes.
  Eigen::AlignedBox3d box(frame.T_world_camera.translation());
  for (double u : {-0.5, width - 0.5})
    for (double v : {-0.5, height - 0.5})
      box.extend(frame.T_world_camera * Eigen::Vector3d(far_m * (u - cx) / fx, far_m * (v - cy) / fy, far_m));
  const double root_m = kRootCells * cell_m;
  std::array<int64_t, 3> lo, hi;
  for (int a = 0; a < 3; ++a) {
    lo[a] = static_cast<int64_t>(std::floor(box.min()[a] / root_m));
    hi[a] = static_cast<int64_t>(std::floor(box.max()[a] / root_m));
  }
  std::vector<CellIndex> roots;
  for (int64_t z = lo[2]; z <= hi[2]; ++z)
    for (int64_t y = lo[1]; y <= hi[1]; ++y)
      for (int64_t x = lo[0]; x <= hi[0]; ++x)
        roots.push_back({static_cast<int32_t>(x * kRootCells), static_cast<int32_t>(y * kRootCells),
                         static_cast<int32_t>(z * kRootCells)});

  const double half_diagonal = 0.5 * std::sqrt(3.0) * cell_m;
  const int top_level = static_cast<int>(pyramid_.size()) - 1;
  std::vector<RootOutput> outputs(roots.size());
  pool_->parallelFor(roots.size(), 1, [&](size_t begin, size_t end) {
    for (size_t r = begin; r < end; ++r) {
      RootOutput& out = outputs[r];
      const CellIndex root = roots[r];
      auto markFree = [&](const CellIndex& o, int size) {
        for (int z = o.z; z < o.z + size; ++z)
          for (int y = o.y; y < o.y + size; ++y)
            for (int x = o.x; x < o.x + size; ++x) {
              const int lx = x - root.x, ly = y - root.y, lz = z - root.z;
              const int b = lx / 8 + kRootBlocks * (ly / 8 + kRootBlocks * (lz / 8));
              PlanningBlock::set(&out.blocks[b], PlanningBlock::index(lx % 8, ly % 8, lz % 8), true);
            }
        out.stats.cells_seen_free += static_cast<uint64_t>(size) * size * size;
        out.any = true;
      };
      // Depth-first over the node's octants.
      auto visit = [&](auto&& self, const CellIndex& o, int size) -> void {
        ++out.stats.nodes_visited;
        const Eigen::Vector3d centre_w((o.x + 0.5 * size) * cell_m, (o.y + 0.5 * size) * cell_m,
                                       (o.z + 0.5 * size) * cell_m);
        const Eigen::Vector3d c = T_camera_world * centre_w;
        const double radius = size * half_diagonal;
        const double z_near = c.z() - radius, z_far = c.z() + radius;
        if (z_far <= 0.0 || z_near >= far_m) return;
        auto split = [&] {
          const int h = size / 2;
          for (int k = 0; k < 2; ++k)
            for (int j = 0; j < 2; ++j)
              for (int i = 0; i < 2; ++i) self(self, o.offset(i * h, j * h, k * h), h);
        };
        if (z_near < 1e-3) {
          if (size > 1) split();
          return;
        }
        // The bounding sphere's footprint: u = fx·x/z + cx over x ∈ [c.x ± r], z ∈ [z_near, z_far].
        auto extent = [z_near, z_far](double f, double principal, double lo_x, double hi_x, double* lo_px,
                                      double* hi_px) {
          *lo_px = f * lo_x / (lo_x >= 0.0 ? z_far : z_near) + principal;
          *hi_px = f * hi_x / (hi_x >= 0.0 ? z_near : z_far) + principal;
        };
        double u_lo, u_hi, v_lo, v_hi;
        extent(fx, cx, c.x() - radius, c.x() + radius, &u_lo, &u_hi);
        extent(fy, cy, c.y() - radius, c.y() + radius, &v_lo, &v_hi);
        if (u_hi < -0.5 || v_hi < -0.5 || u_lo > width - 0.5 || v_lo > height - 0.5) return;  // out of view
        if (u_lo < -0.5 || v_lo < -0.5 || u_hi > width - 0.5 || v_hi > height - 0.5) {
          if (size > 1) split();  // partly out of view: its parts inside may still be free
          return;
        }
        const int px0 = std::clamp(static_cast<int>(std::floor(u_lo + 0.5)), 0, width - 1);
        const int px1 = std::clamp(static_cast<int>(std::floor(u_hi + 0.5)), 0, width - 1);
        const int py0 = std::clamp(static_cast<int>(std::floor(v_lo + 0.5)), 0, height - 1);
        const int py1 = std::clamp(static_cast<int>(std::floor(v_hi + 0.5)), 0, height - 1);
        int level = 0;
        while (level < top_level && ((px1 / pyramid_[level].tile_px - px0 / pyramid_[level].tile_px > 3) ||
                                     (py1 / pyramid_[level].tile_px - py0 / pyramid_[level].tile_px > 3)))
          ++level;
        const TileLevel& tiles = pyramid_[level];
        float min_free = std::numeric_limits<float>::infinity(), max_free = 0.0f;
        for (int ty = py0 / tiles.tile_px; ty <= py1 / tiles.tile_px; ++ty)
          for (int tx = px0 / tiles.tile_px; tx <= px1 / tiles.tile_px; ++tx) {
            const size_t t = static_cast<size_t>(ty) * tiles.tiles_x + tx;
            min_free = std::min(min_free, tiles.min_free_m[t]);
            max_free = std::max(max_free, tiles.max_free_m[t]);
          }
        if (min_free > z_far) {
          markFree(o, size);
          return;
        }
        if (max_free <= z_near) return;  // behind every free depth it can see
        if (size > 1) split();
      };
      visit(visit, root, kRootCells);
    }
  });
  for (size_t r = 0; r < roots.size(); ++r) {
    stats.nodes_visited += outputs[r].stats.nodes_visited;
    stats.cells_seen_free += outputs[r].stats.cells_seen_free;
    if (!outputs[r].any) continue;
    for (int b = 0; b < kRootBlocks * kRootBlocks * kRootBlocks; ++b) {
      if (!PlanningBlock::any(outputs[r].blocks[b])) continue;
      const BlockKey key{roots[r].x / 8 + b % kRootBlocks, roots[r].y / 8 + (b / kRootBlocks) % kRootBlocks,
                         roots[r].z / 8 + b / (kRootBlocks * kRootBlocks)};
      seen_free->emplace_back(key, outputs[r].blocks[b]);
    }
  }
  std::sort(seen_free->begin(), seen_free->end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return stats;
}

}  // namespace stereo_fusion
