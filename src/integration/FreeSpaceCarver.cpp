#include "stereo_fusion/integration/FreeSpaceCarver.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "stereo_fusion/integration/FusionKernels.h"
#include "stereo_fusion/integration/FusionMath.h"

namespace stereo_fusion {

namespace {

constexpr int kTilePx = 16;

/// The frustum of a frame in camera coordinates, as half-spaces a·p ≥ 0 (a point is in view
/// only if it satisfies all): the four image borders at ±0.5 px beyond the outer pixel centres,
/// and the depth range (0, far].
struct Frustum {
  std::array<Eigen::Vector4f, 6> planes;  // (a, b, c, d): a·x + b·y + c·z + d ≥ 0

  Frustum(const FusionFrame& f, float far_m) {
    // u = fx·x/z + cx ≥ −0.5  ⇔  fx·x + (cx + 0.5)·z ≥ 0 (z > 0); likewise for the others.
    planes[0] = {f.fx_px, 0.0f, f.cx_px + 0.5f, 0.0f};
    planes[1] = {-f.fx_px, 0.0f, f.u_end_px - f.cx_px, 0.0f};
    planes[2] = {0.0f, f.fy_px, f.cy_px + 0.5f, 0.0f};
    planes[3] = {0.0f, -f.fy_px, f.v_end_px - f.cy_px, 0.0f};
    planes[4] = {0.0f, 0.0f, 1.0f, 0.0f};
    planes[5] = {0.0f, 0.0f, -1.0f, far_m};
  }

  /// False only if every corner of the box lies outside one plane: nothing in it is in view.
  bool mayIntersect(const std::array<Eigen::Vector3f, 8>& corners_c) const {
    for (const Eigen::Vector4f& p : planes) {
      bool all_outside = true;
      for (const Eigen::Vector3f& c : corners_c)
        if (p.head<3>().dot(c) + p.w() >= 0.0f) {
          all_outside = false;
          break;
        }
      if (all_outside) return false;
    }
    return true;
  }
};

std::array<Eigen::Vector3f, 8> boxCornersInCamera(const Eigen::Isometry3d& T_camera_world,
                                                  const Eigen::AlignedBox3d& box_world) {
  std::array<Eigen::Vector3f, 8> corners;
  for (int c = 0; c < 8; ++c)
    corners[c] =
        (T_camera_world * box_world.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)))
            .cast<float>();
  return corners;
}

}  // namespace

FreeSpaceCarver::FreeSpaceCarver(const CarveConfig& config, ThreadPool* pool)
    : config_(config), pool_(pool) {}

float FreeSpaceCarver::freeDepth(const float* depth_m, int width_px, int height_px, int window_px,
                                 int u, int v) {
  float smallest = std::numeric_limits<float>::infinity();
  for (int y = std::max(v - window_px, 0); y <= std::min(v + window_px, height_px - 1); ++y)
    for (int x = std::max(u - window_px, 0); x <= std::min(u + window_px, width_px - 1); ++x) {
      const float d = depth_m[static_cast<size_t>(y) * width_px + x];
      if (!(d > 0.0f)) return 0.0f;  // a pixel without a measurement: no free space here
      smallest = std::min(smallest, d);
    }
  return smallest;
}

void FreeSpaceCarver::buildTileMaxima(const float* depth_m, int width_px, int height_px) {
  tiles_x_ = (width_px + kTilePx - 1) / kTilePx;
  tiles_y_ = (height_px + kTilePx - 1) / kTilePx;
  tile_max_depth_m_.assign(static_cast<size_t>(tiles_x_) * tiles_y_, 0.0f);
  pool_->parallelFor(static_cast<size_t>(tiles_y_), 4, [&](size_t begin, size_t end) {
    for (size_t ty = begin; ty < end; ++ty) {
      float* tiles = tile_max_depth_m_.data() + ty * tiles_x_;
      const int v_end = std::min(static_cast<int>(ty + 1) * kTilePx, height_px);
      for (int v = static_cast<int>(ty) * kTilePx; v < v_end; ++v) {
        const float* row = depth_m + static_cast<size_t>(v) * width_px;
        for (int tx = 0; tx < tiles_x_; ++tx) {
          float m = tiles[tx];
          const int u_end = std::min((tx + 1) * kTilePx, width_px);
          for (int u = tx * kTilePx; u < u_end; ++u) m = row[u] > m ? row[u] : m;  // NaN never wins
          tiles[tx] = m;
        }
      }
    }
  });
}

CarveStats FreeSpaceCarver::carve(const StereoFrame& frame, const MeasurementImage& measurements,
                                  const BlockOctree& octree, const std::vector<VoxelBlock*>& queued,
                                  std::vector<VoxelBlock*>* carved) {
  carved->clear();
  CarveStats stats;
  const FusionFrame f = makeFusionFrame(frame, config_.fusion, measurements);
  buildTileMaxima(f.depth_m, f.width_px, f.height_px);
  float far_m = 0.0f;
  for (float t : tile_max_depth_m_) far_m = std::max(far_m, t);
  if (!(far_m > 0.0f)) return stats;

  // Fusion's blocks get their free space from fusion: mark them by row.
  if (++stamp_ == 0) {
    std::fill(queued_stamp_.begin(), queued_stamp_.end(), 0u);
    stamp_ = 1;
  }
  if (queued_stamp_.size() < octree.rowCount()) queued_stamp_.resize(octree.rowCount(), 0u);
  for (const VoxelBlock* block : queued) queued_stamp_[block->row] = stamp_;

  // The blocks in view: octree nodes outside the frustum are skipped whole.
  const Frustum frustum(f, far_m);
  candidates_.clear();
  octree.collectBlocks(
      [&](const Eigen::AlignedBox3d& box_world) {
        return frustum.mayIntersect(boxCornersInCamera(f.T_camera_world, box_world));
      },
      &candidates_, pool_);
  // Only blocks with a corner nearer than the largest depth under their footprint can hold a
  // voxel in front of its free depth (d < 0 ⇔ F > z_c, and F is at most the pixel's own depth):
  // the others are behind every surface they face.
  const double block_m = octree.blockSize();
  auto mayBeSeenThrough = [&](const VoxelBlock& block) {
    const Eigen::Vector3d origin = octree.blockOrigin(block.key);
    const auto corners = boxCornersInCamera(
        f.T_camera_world, Eigen::AlignedBox3d(origin, origin + Eigen::Vector3d::Constant(block_m)));
    float z_near = std::numeric_limits<float>::infinity();
    float u_lo = std::numeric_limits<float>::infinity(), u_hi = -u_lo, v_lo = u_lo, v_hi = -u_lo;
    for (const Eigen::Vector3f& c : corners) {
      z_near = std::min(z_near, c.z());
      if (!(c.z() > 1e-3f)) return true;  // reaches the camera plane: no footprint, visit it
      u_lo = std::min(u_lo, f.fx_px * c.x() / c.z() + f.cx_px);
      u_hi = std::max(u_hi, f.fx_px * c.x() / c.z() + f.cx_px);
      v_lo = std::min(v_lo, f.fy_px * c.y() / c.z() + f.cy_px);
      v_hi = std::max(v_hi, f.fy_px * c.y() / c.z() + f.cy_px);
    }
    // The voxels' nearest pixels lie within the corners' box (a convex hull's projection).
    // Clamped in float first: a corner just in front of the camera projects far beyond int.
    auto tile = [](float coordinate_px, int size_px) {
      const float clamped = std::clamp(coordinate_px + 0.5f, 0.0f, static_cast<float>(size_px - 1));
      return static_cast<int>(std::floor(clamped)) / kTilePx;
    };
    const int tx0 = tile(u_lo, f.width_px), tx1 = tile(u_hi, f.width_px);
    const int ty0 = tile(v_lo, f.height_px), ty1 = tile(v_hi, f.height_px);
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx)
        if (tile_max_depth_m_[static_cast<size_t>(ty) * tiles_x_ + tx] > z_near) return true;
    return false;
  };
  // Decided in parallel (a block's own test), then compacted in order.
  keep_.assign(candidates_.size(), 0);
  pool_->parallelFor(candidates_.size(), 256, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      keep_[i] = queued_stamp_[candidates_[i]->row] != stamp_ && mayBeSeenThrough(*candidates_[i]);
  });
  size_t kept = 0;
  for (size_t i = 0; i < candidates_.size(); ++i)
    if (keep_[i]) candidates_[kept++] = candidates_[i];
  candidates_.resize(kept);
  stats.blocks_visited = candidates_.size();

  const float keep = static_cast<float>(1.0 - config_.fusion.free_space_decay);
  const int window = config_.free_space_window_px;
  block_updates_.assign(candidates_.size(), 0);
  pool_->parallelFor(candidates_.size(), 8, [&](size_t begin, size_t end) {
    for (size_t b = begin; b < end; ++b) {
      VoxelBlock* block = candidates_[b];
      const Eigen::Vector3f origin_c =
          (f.T_camera_world * octree.blockOrigin(block->key)).cast<float>();
      uint64_t updates = 0;
      for (int level = 0; level < kNumLevels; ++level) {
        Voxel* voxels = block->levelIfAllocated(level);
        if (voxels == nullptr) continue;
        const FusionFrame::Level& geometry = f.levels[level];
        const int side = levelSide(level);
        const Eigen::Vector3f first =
            origin_c + 0.5f * (geometry.ex_m + geometry.ey_m + geometry.ez_m);
        for (int k = 0; k < side; ++k)
          for (int j = 0; j < side; ++j)
            for (int i = 0; i < side; ++i) {
              Voxel& voxel = voxels[VoxelBlock::indexInLevel(side, i, j, k)];
              if (!(voxel.weight > 0.0f)) continue;  // unknown stays unknown
              const Eigen::Vector3f p = first + static_cast<float>(i) * geometry.ex_m +
                                        static_cast<float>(j) * geometry.ey_m +
                                        static_cast<float>(k) * geometry.ez_m;
              size_t pixel;  // the pixel fusion would read
              if (!nearestPixel(f, p, &pixel)) continue;
              // The pixel's own depth bounds its free depth: most voxels stop here.
              if (!(f.depth_m[pixel] > p.z())) continue;
              const int iu = static_cast<int>(pixel % f.width_px),
                        iv = static_cast<int>(pixel / f.width_px);
              const float free_depth =
                  freeDepth(f.depth_m, f.width_px, f.height_px, window, iu, iv);
              if (!(free_depth > p.z())) continue;  // not in front (or no measurement near)
              const int measurement_level = levelForDepth(free_depth, f.thresholds);
              const float truncation = geometry.truncation_m[measurement_level];
              const float sdf = signedDistanceAlongRay(p.x(), p.y(), p.z(), free_depth);
              if (!(sdf < -truncation)) continue;  // within fusion's band: fusion's to decide
              const float w =
                  measurementWeight(f.weight_mode, -truncation, f.delta_m[measurement_level],
                                    truncation, free_depth, f.depth_weight_reference_m);
              if (!(w > 0.0f)) continue;
              voxel.weight *= keep;
              fuseMeasurement(&voxel, -truncation, w, f.max_weight, nullptr);
              ++updates;
            }
      }
      block_updates_[b] = updates;
    }
  });
  for (size_t b = 0; b < candidates_.size(); ++b) {
    if (block_updates_[b] == 0) continue;
    stats.voxels_carved += block_updates_[b];
    carved->push_back(candidates_[b]);
  }
  stats.blocks_carved = carved->size();
  std::sort(carved->begin(), carved->end(),
            [](const VoxelBlock* a, const VoxelBlock* b) { return a->key < b->key; });
  return stats;
}

}  // namespace stereo_fusion
