#include "stereo_fusion/integration/SurfaceFuser.h"

#include <cmath>

#include "stereo_fusion/integration/FusionMath.h"

namespace stereo_fusion {

SurfaceFuser::SurfaceFuser(const MapperConfig& config, ThreadPool* pool)
    : config_(config), pool_(pool) {}

uint64_t SurfaceFuser::fuseBlock(const StereoFrame& frame, const BlockOctree& octree,
                                 VoxelBlock* block) const {
  const StereoCamera& cam = frame.camera;
  const Eigen::Isometry3d T_camera_world = frame.T_world_camera.inverse();
  // Voxel centres are stepped from the block origin in camera coordinates: the origin is
  // transformed in double (world coordinates may be large), the small offsets in float.
  const Eigen::Vector3f origin_c = (T_camera_world * octree.blockOrigin(block->key)).cast<float>();
  const Eigen::Matrix3f R_cw = T_camera_world.linear().cast<float>();
  const float fx = static_cast<float>(cam.fx()), fy = static_cast<float>(cam.fy());
  const float cx = static_cast<float>(cam.cx()), cy = static_cast<float>(cam.cy());
  const float fb = static_cast<float>(cam.fx() * cam.baseline());
  const float min_depth = static_cast<float>(config_.min_depth_m);
  const float max_depth = static_cast<float>(config_.max_depth_m);
  const float voxel = static_cast<float>(config_.voxel_size_m);
  const float max_weight = static_cast<float>(config_.max_weight);
  const float z_ref = static_cast<float>(config_.depth_weight_reference_m);
  const int width = cam.width(), height = cam.height();
  const bool use_color = config_.use_color && !frame.color.empty();
  const bool grey = use_color && frame.color.channels() == 1;

  // Block-level depth test: a voxel is only updated by a surface at depth ≥ z_voxel − Φ
  // (eq. 3.15 with sdf ≤ Φ), and a level finer than the measurement's is skipped. When even
  // the block's nearest corner is so far that every possible measurement is coarser than a
  // level, none of that level's voxels can change: skip it without projecting them.
  const float block_m = voxel * kFinestSide;
  float nearest_z = origin_c.z();
  for (int c = 1; c < 8; ++c)
    nearest_z = std::min(nearest_z, origin_c.z() + block_m * ((c & 1 ? R_cw(2, 0) : 0.0f) +
                                                            (c & 2 ? R_cw(2, 1) : 0.0f) +
                                                            (c & 4 ? R_cw(2, 2) : 0.0f)));
  const float max_truncation =
      std::max(static_cast<float>(config_.truncation_vox), kMinBandVoxels) * levelScale(kNumLevels - 1) * voxel;
  // Margin: the voxel loop computes depths with other float roundings.
  const double nearest_surface_m = static_cast<double>(nearest_z) - max_truncation - 1e-3;
  const int first_level = levelForDepth(nearest_surface_m, config_.levels);

  uint64_t updates = 0;
  for (int level = first_level; level < kNumLevels; ++level) {
    const int side = levelSide(level);
    const float level_voxel = voxel * levelScale(level);
    const Eigen::Vector3f ex = R_cw.col(0) * level_voxel;
    const Eigen::Vector3f ey = R_cw.col(1) * level_voxel;
    const Eigen::Vector3f ez = R_cw.col(2) * level_voxel;
    const Eigen::Vector3f first = origin_c + 0.5f * (ex + ey + ez);
    // A coarse level fed by near measurements still needs values on both sides of the surface
    // at its own spacing: its band is never thinner than kMinBandVoxels of its voxels.
    const float min_truncation = kMinBandVoxels * level_voxel;
    Voxel* voxels = &block->voxels[levelOffset(level)];
    for (int k = 0; k < side; ++k) {
      for (int j = 0; j < side; ++j) {
        for (int i = 0; i < side; ++i) {
          const Eigen::Vector3f p = first + static_cast<float>(i) * ex +
                                    static_cast<float>(j) * ey + static_cast<float>(k) * ez;
          if (!(p.z() > 0.0f)) continue;
          // Eq. 3.12–3.14: nearest pixel of the voxel centre's projection. Bounds are checked
          // in float first: u, v can be huge or infinite for z_c near 0.
          const float u = fx * p.x() / p.z() + cx;
          const float v = fy * p.y() / p.z() + cy;
          if (!(u >= -0.5f && v >= -0.5f && u < width - 0.5f && v < height - 0.5f)) continue;
          const int iu = static_cast<int>(std::floor(u + 0.5f));
          const int iv = static_cast<int>(std::floor(v + 0.5f));
          if (iu < 0 || iv < 0 || iu >= width || iv >= height) continue;
          const float d = frame.disparity_px.at<float>(iv, iu);
          if (!(d > 0.0f) || !std::isfinite(d)) continue;
          const float surface_depth = fb / d;
          if (!(surface_depth >= min_depth && surface_depth <= max_depth)) continue;
          const int measurement_level = levelForDepth(surface_depth, config_.levels);
          if (level < measurement_level) continue;  // too fine for this measurement
          const float scale = static_cast<float>(levelScale(measurement_level));
          const float truncation = std::max(static_cast<float>(config_.truncation_vox) * scale * voxel, min_truncation);
          const float delta = static_cast<float>(config_.weight_falloff_start_vox) * scale * voxel;
          const float sdf = signedDistanceAlongRay(p.x(), p.y(), p.z(), surface_depth);
          if (sdf > truncation) continue;  // far behind the surface: unobserved
          const float w = measurementWeight(config_.weight_mode, sdf, delta, truncation,
                                            surface_depth, z_ref);
          if (!(w > 0.0f)) continue;
          const uint8_t* rgb = nullptr;
          uint8_t grey_rgb[3];
          if (use_color) {
            if (grey) {
              grey_rgb[0] = grey_rgb[1] = grey_rgb[2] = frame.color.at<uint8_t>(iv, iu);
              rgb = grey_rgb;
            } else {
              rgb = frame.color.ptr<uint8_t>(iv) + 3 * iu;
            }
          }
          fuseMeasurement(&voxels[i + j * side + k * side * side], std::max(sdf, -truncation), w,
                          max_weight, rgb);
          ++updates;
        }
      }
    }
  }
  return updates;
}

FusionStats SurfaceFuser::fuse(const StereoFrame& frame, const BlockOctree& octree,
                               const std::vector<VoxelBlock*>& blocks, uint64_t frame_index,
                               std::vector<VoxelBlock*>* updated) {
  per_block_updates_.assign(blocks.size(), 0);
  pool_->parallelFor(blocks.size(), 8, [&](size_t begin, size_t end) {
    for (size_t b = begin; b < end; ++b) per_block_updates_[b] = fuseBlock(frame, octree, blocks[b]);
  });
  FusionStats stats;
  updated->clear();
  for (size_t b = 0; b < blocks.size(); ++b) {
    if (per_block_updates_[b] == 0) continue;
    blocks[b]->last_update_frame = frame_index;
    updated->push_back(blocks[b]);
    stats.voxels_updated += per_block_updates_[b];
  }
  stats.blocks_updated = updated->size();
  return stats;
}

}  // namespace stereo_fusion
