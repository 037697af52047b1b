#include "stereo_fusion/planning/FreeSpaceRecorder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace stereo_fusion {

namespace {

constexpr int kTileShift = 3;
constexpr int kTilePx = 1 << kTileShift;
/// Edge of the octree's roots in cells: 4³ planning blocks.
constexpr int kRootCells = 16;
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
  base.tile_shift = kTileShift;
  base.tiles_x = (width + kTilePx - 1) / kTilePx;
  base.tiles_y = (height + kTilePx - 1) / kTilePx;
  base.bounds.assign(static_cast<size_t>(base.tiles_x) * base.tiles_y, {0.0f, 0.0f, 0.0f});
  const float* depth = measurements.depths();
  pool_->parallelFor(static_cast<size_t>(base.tiles_y), 4, [&](size_t begin, size_t end) {
    for (size_t ty = begin; ty < end; ++ty)
      for (int tx = 0; tx < base.tiles_x; ++tx) {
        float lo = std::numeric_limits<float>::infinity(), hi = 0.0f;
        bool said = false, unmeasured_pixel = false;
        for (int v = static_cast<int>(ty) * kTilePx;
             v < std::min(static_cast<int>(ty + 1) * kTilePx, height); ++v)
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
        const float min_free = said ? std::max(lo, 0.0f) : 0.0f;
        base.bounds[ty * base.tiles_x + tx] = {min_free, said ? std::max(hi, 0.0f) : 0.0f,
                                               min_free};
      }
  });
  // Coarser levels: min and max over 2×2 children, until one tile is left.
  while (pyramid_.back().tiles_x > 1 || pyramid_.back().tiles_y > 1) {
    const TileLevel& fine = pyramid_.back();
    TileLevel coarse;
    coarse.tile_shift = fine.tile_shift + 1;
    coarse.tiles_x = (fine.tiles_x + 1) / 2;
    coarse.tiles_y = (fine.tiles_y + 1) / 2;
    coarse.bounds.assign(static_cast<size_t>(coarse.tiles_x) * coarse.tiles_y,
                         {std::numeric_limits<float>::infinity(), 0.0f, 0.0f});
    for (int y = 0; y < fine.tiles_y; ++y)
      for (int x = 0; x < fine.tiles_x; ++x) {
        const TileLevel::Bounds& f = fine.bounds[static_cast<size_t>(y) * fine.tiles_x + x];
        TileLevel::Bounds& c = coarse.bounds[static_cast<size_t>(y / 2) * coarse.tiles_x + x / 2];
        c.min_free_m = std::min(c.min_free_m, f.min_free_m);
        c.max_free_m = std::max(c.max_free_m, f.max_free_m);
        c.max_min_free_m = std::max(c.max_min_free_m, f.max_min_free_m);
      }
    pyramid_.push_back(std::move(coarse));
  }
}

FreeSpaceStats FreeSpaceRecorder::record(
    const StereoFrame& frame, const MeasurementImage& measurements,
    std::vector<std::pair<BlockKey, PlanningBlock::Bits>>* seen_free) {
  seen_free->clear();
  FreeSpaceStats stats;
  if (measurements.width() <= 0 || measurements.height() <= 0) return stats;
  buildTiles(measurements);
  const double far_m = pyramid_.back().bounds[0].max_free_m;
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
      box.extend(frame.T_world_camera *
                 Eigen::Vector3d(far_m * (u - cx) / fx, far_m * (v - cy) / fy, far_m));
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

  const int top_level = static_cast<int>(pyramid_.size()) - 1;
  std::vector<RootOutput> outputs(roots.size());
  pool_->parallelFor(roots.size(), 1, [&](size_t begin, size_t end) {
    for (size_t r = begin; r < end; ++r) {
      RootOutput& out = outputs[r];
      const CellIndex root = roots[r];
      // A block's bits are one 64-bit word per z slice, a byte per row of x
      // (PlanningBlock::index()).
      auto markFree = [&](const CellIndex& o, int size) {
        const int lx = o.x - root.x, ly = o.y - root.y, lz = o.z - root.z;
        if (size >= PlanningBlock::kSide) {  // whole blocks
          for (int bz = lz / 8; bz < (lz + size) / 8; ++bz)
            for (int by = ly / 8; by < (ly + size) / 8; ++by)
              for (int bx = lx / 8; bx < (lx + size) / 8; ++bx)
                out.blocks[bx + kRootBlocks * (by + kRootBlocks * bz)].fill(~uint64_t{0});
        } else {  // inside one block
          PlanningBlock::Bits& bits =
              out.blocks[lx / 8 + kRootBlocks * (ly / 8 + kRootBlocks * (lz / 8))];
          const uint64_t row = ((uint64_t{1} << size) - 1) << (lx % 8);
          uint64_t slice = 0;
          for (int y = ly % 8; y < ly % 8 + size; ++y) slice |= row << (8 * y);
          for (int z = lz % 8; z < lz % 8 + size; ++z) bits[z] |= slice;
        }
        out.stats.cells_seen_free += static_cast<uint64_t>(size) * size * size;
        out.any = true;
      };
      // Depth-first over the node's octants. A node is its minimum corner in camera
      // coordinates (float, relative to the camera: precise far from the world origin too) and
      // its edge. The frustum's five planes (image borders at ±0.5 px, z ≥ kMinDepthM) classify
      // it with a dot product each — outside one: nothing of it is seen; inside all: its
      // footprint and depth range come from its extent in camera coordinates.
      const Eigen::Matrix3f R = T_camera_world.linear().cast<float>();
      const Eigen::Vector3f axis_x = R.col(0) * static_cast<float>(cell_m),
                            axis_y = R.col(1) * static_cast<float>(cell_m),
                            axis_z = R.col(2) * static_cast<float>(cell_m);
      const float fxf = static_cast<float>(fx), fyf = static_cast<float>(fy),
                  cxf = static_cast<float>(cx), cyf = static_cast<float>(cy),
                  far_f = static_cast<float>(far_m);
      // Half extent of a one-cell node along each camera axis.
      const Eigen::Vector3f half_extent =
          0.5f * (axis_x.cwiseAbs() + axis_y.cwiseAbs() + axis_z.cwiseAbs());
      constexpr float kMinDepthM = 1e-3f;
      const std::array<Eigen::Vector4f, 5> planes = {
          Eigen::Vector4f(fxf, 0.0f, cxf + 0.5f, 0.0f),
          Eigen::Vector4f(-fxf, 0.0f, width - 0.5f - cxf, 0.0f),
          Eigen::Vector4f(0.0f, fyf, cyf + 0.5f, 0.0f),
          Eigen::Vector4f(0.0f, -fyf, height - 0.5f - cyf, 0.0f),
          Eigen::Vector4f(0.0f, 0.0f, 1.0f, -kMinDepthM)};
      std::array<float, 5> plane_extent;  // a one-cell node's extent along each plane's normal
      for (int p = 0; p < 5; ++p) plane_extent[p] = planes[p].head<3>().cwiseAbs().dot(half_extent);
      // `bounds`: for a child of a node inside the view, that node's free-depth range. The
      // child's footprint lies within its parent's, so a depth beyond the parent's largest free
      // depth is behind for the child too, and one before its smallest is free: most children of
      // a node astride a surface are decided without a footprint of their own.
      const bool skip_past_minima = params_.skip_past_tile_minima;
      struct ParentBounds {
        float min_free_m, max_free_m, max_min_free_m;
      };
      auto visit = [&](auto&& self, const CellIndex& o, const Eigen::Vector3f& corner_c, int size,
                       const ParentBounds* bounds) -> void {
        ++out.stats.nodes_visited;
        const float s = static_cast<float>(size);
        const Eigen::Vector3f c = corner_c + 0.5f * s * (axis_x + axis_y + axis_z);
        const float z_near = c.z() - s * half_extent.z(), z_far = c.z() + s * half_extent.z();
        if (z_far <= 0.0f || z_near >= far_f) return;
        bool inside = true;
        if (bounds) {  // inside the view like its parent
          if (z_near >= bounds->max_free_m) return;
          if (skip_past_minima && z_near >= bounds->max_min_free_m) return;
          if (z_far < bounds->min_free_m) {
            markFree(o, size);
            return;
          }
        } else {
          for (int p = 0; p < 5; ++p) {
            const float d = planes[p].head<3>().dot(c) + planes[p].w(), r = s * plane_extent[p];
            if (d + r < 0.0f) return;  // out of view
            inside = inside && d - r >= 0.0f;
          }
        }
        auto split = [&](const ParentBounds* child_bounds) {
          const int h = size / 2;
          const float hs = static_cast<float>(h);
          for (int k = 0; k < 2; ++k)
            for (int j = 0; j < 2; ++j)
              for (int i = 0; i < 2; ++i)
                self(self, o.offset(i * h, j * h, k * h),
                     corner_c + hs * (float(i) * axis_x + float(j) * axis_y + float(k) * axis_z), h,
                     child_bounds);
        };
        // Footprint: u = fx·x/z + cx over the node's extent x ∈ [c.x ± ·], z ∈ [z_near, z_far];
        // clipped to the image for a node partly out of view.
        if (!inside && (size == 1 || z_near <= kMinDepthM)) {
          if (size > 1) split(nullptr);  // reaches the camera plane: no footprint
          return;
        }
        const float x_lo = c.x() - s * half_extent.x(), x_hi = c.x() + s * half_extent.x();
        const float y_lo = c.y() - s * half_extent.y(), y_hi = c.y() + s * half_extent.y();
        const float inv_near = 1.0f / z_near, inv_far = 1.0f / z_far;
        const float u_lo = fxf * x_lo * (x_lo >= 0.0f ? inv_far : inv_near) + cxf;
        const float u_hi = fxf * x_hi * (x_hi >= 0.0f ? inv_near : inv_far) + cxf;
        const float v_lo = fyf * y_lo * (y_lo >= 0.0f ? inv_far : inv_near) + cyf;
        const float v_hi = fyf * y_hi * (y_hi >= 0.0f ? inv_near : inv_far) + cyf;
        // Clamped in float first (a node near the camera plane projects far beyond int); then
        // + 0.5 truncates as floor (≥ 0).
        auto pixel = [](float coordinate_px, int size_px) {
          return static_cast<int>(
              std::clamp(coordinate_px + 0.5f, 0.0f, static_cast<float>(size_px - 1)));
        };
        const int px0 = pixel(u_lo, width), px1 = pixel(u_hi, width);
        const int py0 = pixel(v_lo, height), py1 = pixel(v_hi, height);
        int level = 0;
        while (level < top_level &&
               (((px1 >> pyramid_[level].tile_shift) - (px0 >> pyramid_[level].tile_shift) > 3) ||
                ((py1 >> pyramid_[level].tile_shift) - (py0 >> pyramid_[level].tile_shift) > 3)))
          ++level;
        const TileLevel& tiles = pyramid_[level];
        float min_free = std::numeric_limits<float>::infinity(), max_free = 0.0f,
              max_min_free = 0.0f;
        // (Pixels are ≥ 0: a shift is their division by the tile size, without its cost.)
        for (int ty = py0 >> tiles.tile_shift; ty <= py1 >> tiles.tile_shift; ++ty)
          for (int tx = px0 >> tiles.tile_shift; tx <= px1 >> tiles.tile_shift; ++tx) {
            const TileLevel::Bounds& t = tiles.bounds[static_cast<size_t>(ty) * tiles.tiles_x + tx];
            min_free = std::min(min_free, t.min_free_m);
            max_free = std::max(max_free, t.max_free_m);
            max_min_free = std::max(max_min_free, t.max_min_free_m);
          }
        if (max_free <= z_near) return;  // behind every free depth it can see
        if (!inside) {
          split(nullptr);  // partly out of view: its parts inside may still be free
          return;
        }
        if (min_free > z_far) {
          markFree(o, size);
          return;
        }
        // Every part of the node sees some finest tile of its footprint, so frees nothing
        // beyond the largest of their smallest free depths: past it, nothing here is free.
        if (skip_past_minima && z_near >= max_min_free) return;
        const ParentBounds mine{min_free, max_free, max_min_free};
        if (size > 1) split(&mine);
      };
      const Eigen::Vector3f root_c =
          (T_camera_world * Eigen::Vector3d(root.x * cell_m, root.y * cell_m, root.z * cell_m))
              .cast<float>();
      visit(visit, root, root_c, kRootCells, nullptr);
    }
  });
  for (size_t r = 0; r < roots.size(); ++r) {
    stats.nodes_visited += outputs[r].stats.nodes_visited;
    stats.cells_seen_free += outputs[r].stats.cells_seen_free;
    if (!outputs[r].any) continue;
    for (int b = 0; b < kRootBlocks * kRootBlocks * kRootBlocks; ++b) {
      if (!PlanningBlock::any(outputs[r].blocks[b])) continue;
      const BlockKey key{roots[r].x / 8 + b % kRootBlocks,
                         roots[r].y / 8 + (b / kRootBlocks) % kRootBlocks,
                         roots[r].z / 8 + b / (kRootBlocks * kRootBlocks)};
      seen_free->emplace_back(key, outputs[r].blocks[b]);
    }
  }
  std::sort(seen_free->begin(), seen_free->end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return stats;
}

}  // namespace stereo_fusion
