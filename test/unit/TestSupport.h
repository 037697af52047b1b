#pragma once
// Helpers shared by the unit tests: a standard camera, frames rendered from analytic scenes,
// map snapshots for equality checks, and zero-crossing extraction from the SDF.

#include <Eigen/Geometry>
#include <cstring>
#include <random>
#include <vector>

#include "simulator/AnalyticScene.h"
#include "stereo_fusion/Mapper.h"

namespace stereo_fusion::test {

inline StereoCamera vgaCamera() {
  return *StereoCamera::create(640, 480, 525.0, 525.0, 319.5, 239.5, 0.1);
}

/// A frame of `scene` seen from T_world_camera, with exact disparity plus optional Gaussian
/// disparity noise of `noise_px` (σ, pixels).
inline StereoFrame renderFrame(const sim::AnalyticScene& scene, const StereoCamera& camera,
                               const Eigen::Isometry3d& T_world_camera, double noise_px = 0.0,
                               uint32_t seed = 1) {
  StereoFrame frame;
  frame.camera = camera;
  frame.T_world_camera = T_world_camera;
  cv::Mat depth;
  sim::renderDepthAndColor(scene, camera, T_world_camera, &depth, &frame.color);
  frame.disparity_px = sim::disparityFromDepth(depth, camera);
  if (noise_px > 0) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> noise(0.0f, static_cast<float>(noise_px));
    for (int v = 0; v < frame.disparity_px.rows; ++v)
      for (int u = 0; u < frame.disparity_px.cols; ++u) {
        float& d = frame.disparity_px.at<float>(v, u);
        if (d > 0) d = std::max(d + noise(rng), 0.0f);
      }
  }
  return frame;
}

/// Every block's key, which levels it has allocated and the raw bytes of all its 584 voxels
/// (unallocated levels read as unobserved), sorted by key: equal snapshots ⇔ identical maps.
struct MapSnapshot {
  std::vector<BlockKey> keys;
  std::vector<uint8_t> level_masks;  ///< per block, bit l: level l allocated
  std::vector<Voxel> voxels;         ///< VoxelBlock::kVoxelCount per block
  bool operator==(const MapSnapshot& o) const {
    // memcmp takes no null pointer, not even for 0 bytes (an empty map's vectors have none).
    return keys == o.keys && level_masks == o.level_masks && voxels.size() == o.voxels.size() &&
           (voxels.empty() ||
            std::memcmp(voxels.data(), o.voxels.data(), voxels.size() * sizeof(Voxel)) == 0);
  }
};

inline MapSnapshot snapshot(const BlockOctree& map) {
  MapSnapshot s;
  for (const VoxelBlock* b : map.blocksSortedByKey()) {
    s.keys.push_back(b->key);
    uint8_t mask = 0;
    for (int level = 0; level < kNumLevels; ++level)
      mask |= static_cast<uint8_t>(b->hasLevel(level) << level);
    s.level_masks.push_back(mask);
    for (int n = 0; n < VoxelBlock::kVoxelCount; ++n) s.voxels.push_back(b->voxel(n));
  }
  return s;
}

/// World position of the centre of voxel (i, j, k) of `level` in block `key`.
inline Eigen::Vector3d voxelCentre(const BlockOctree& map, const BlockKey& key, int level, int i,
                                   int j, int k) {
  const double h = map.blockSize() / levelSide(level);
  return map.blockOrigin(key) + Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5) * h;
}

/// Outcome of comparing every block's neighbour links with searches.
struct LinkCheck {
  size_t checked = 0;     ///< (block, offset) pairs compared: 27 per block
  size_t linked = 0;      ///< pairs whose neighbour exists (the block itself included)
  size_t mismatched = 0;  ///< pairs where the link differs from find(key.offset(...))
};

/// For every block and every offset in {-1,0,1}³, BlockOctree::neighbour(block, ...) against
/// find(key.offset(...)), nullptr included.
inline LinkCheck checkNeighbourLinks(const BlockOctree& map) {
  LinkCheck c;
  for (const VoxelBlock* b : map.blocks())
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const VoxelBlock* linked = map.neighbour(*b, dx, dy, dz);
          ++c.checked;
          c.linked += linked != nullptr;
          c.mismatched += linked != map.find(b->key.offset(dx, dy, dz));
        }
  return c;
}

/// Zero crossings of the SDF at `level` between voxel centres adjacent along `axis`
/// (0 = x, 1 = y, 2 = z), both observed, linearly interpolated (the marching cubes rule).
/// Pairs whose values differ by more than two voxel edges are truncation-edge artefacts,
/// not surface crossings, and are skipped.
inline std::vector<Eigen::Vector3d> zeroCrossings(const BlockOctree& map, int level, int axis) {
  std::vector<Eigen::Vector3d> out;
  const int side = levelSide(level);
  const double h = map.blockSize() / side;
  for (const VoxelBlock* b : map.blocksSortedByKey()) {
    for (int k = 0; k < side; ++k)
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
          const Voxel& a = b->at(level, i, j, k);
          int n[3] = {i, j, k};
          n[axis] += 1;
          const VoxelBlock* nb = b;
          if (n[axis] == side) {
            n[axis] = 0;
            int d[3] = {0, 0, 0};
            d[axis] = 1;
            nb = map.neighbour(b->key, d[0], d[1], d[2]);
            if (nb == nullptr) continue;
          }
          const Voxel& c = nb->at(level, n[0], n[1], n[2]);
          if (!(a.weight > 0 && c.weight > 0)) continue;
          if ((a.sdf_m < 0) == (c.sdf_m < 0)) continue;
          if (std::abs(a.sdf_m - c.sdf_m) > 2 * h) continue;
          const double t = a.sdf_m / (a.sdf_m - c.sdf_m);
          Eigen::Vector3d p = voxelCentre(map, b->key, level, i, j, k);
          p[axis] += t * h;
          out.push_back(p);
        }
  }
  return out;
}

inline double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace stereo_fusion::test
