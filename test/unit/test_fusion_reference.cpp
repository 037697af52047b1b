// SurfaceFuser against a reference transcription of the thesis equations that visits every
// voxel of every level of every queued block, with none of the fuser's shortcuts (block-level
// depth test, level skipping). Voxel values must agree bit for bit, so any shortcut that
// drops a real update, or updates what it should not, fails here.

#include <gtest/gtest.h>

#include <cstring>

#include "TestSupport.h"
#include "stereo_fusion/integration/BlockLookup.h"
#include "stereo_fusion/integration/FusionMath.h"
#include "stereo_fusion/integration/SurfaceFuser.h"

namespace stereo_fusion {
namespace {

using test::renderFrame;
using test::vgaCamera;

/// Eq. 3.8–3.15 for one block, every voxel of every level; the float operations are those of
/// SurfaceFuser so that results are comparable bit for bit.
void referenceFuseBlock(const StereoFrame& frame, const BlockOctree& octree, const MapperConfig& config,
                        VoxelBlock* block) {
  const StereoCamera& cam = frame.camera;
  const Eigen::Isometry3d T_camera_world = frame.T_world_camera.inverse();
  const Eigen::Vector3f origin_c = (T_camera_world * octree.blockOrigin(block->key)).cast<float>();
  const Eigen::Matrix3f R_cw = T_camera_world.linear().cast<float>();
  const float fx = static_cast<float>(cam.fx()), fy = static_cast<float>(cam.fy());
  const float cx = static_cast<float>(cam.cx()), cy = static_cast<float>(cam.cy());
  const float fb = static_cast<float>(cam.fx() * cam.baseline());
  const float voxel = static_cast<float>(config.voxel_size_m);
  for (int level = 0; level < kNumLevels; ++level) {
    const int side = levelSide(level);
    const float level_voxel = voxel * levelScale(level);
    const Eigen::Vector3f ex = R_cw.col(0) * level_voxel, ey = R_cw.col(1) * level_voxel,
                          ez = R_cw.col(2) * level_voxel;
    const Eigen::Vector3f first = origin_c + 0.5f * (ex + ey + ez);
    for (int k = 0; k < side; ++k)
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
          const Eigen::Vector3f p = first + static_cast<float>(i) * ex + static_cast<float>(j) * ey +
                                    static_cast<float>(k) * ez;
          if (!(p.z() > 0.0f)) continue;
          const float u = fx * p.x() / p.z() + cx, v = fy * p.y() / p.z() + cy;
          if (!(u >= -0.5f && v >= -0.5f && u < cam.width() - 0.5f && v < cam.height() - 0.5f)) continue;
          const int iu = static_cast<int>(std::floor(u + 0.5f)), iv = static_cast<int>(std::floor(v + 0.5f));
          if (iu < 0 || iv < 0 || iu >= cam.width() || iv >= cam.height()) continue;
          const float d = frame.disparity_px.at<float>(iv, iu);
          if (!(d > 0.0f) || !std::isfinite(d)) continue;
          const float z = fb / d;
          if (!(z >= static_cast<float>(config.min_depth_m) && z <= static_cast<float>(config.max_depth_m))) continue;
          const int m = levelForDepth(z, config.levels);
          if (level < m) continue;
          const float scale = static_cast<float>(levelScale(m));
          const float truncation = std::max(static_cast<float>(config.truncation_vox) * scale * voxel,
                                            SurfaceFuser::kMinBandVoxels * level_voxel);
          const float delta = static_cast<float>(config.weight_falloff_start_vox) * scale * voxel;
          const float sdf = signedDistanceAlongRay(p.x(), p.y(), p.z(), z);
          if (sdf > truncation) continue;
          const float w = measurementWeight(config.weight_mode, sdf, delta, truncation, z,
                                            static_cast<float>(config.depth_weight_reference_m));
          if (!(w > 0.0f)) continue;
          fuseMeasurement(&block->voxels[levelOffset(level) + i + j * side + k * side * side],
                          std::max(sdf, -truncation), w, static_cast<float>(config.max_weight),
                          frame.color.ptr<uint8_t>(iv) + 3 * iu);
        }
  }
}

TEST(FusionReference, FuserEqualsPerVoxelReferenceAcrossAllLevels) {
  // A floor and a wall seen obliquely from 0.5 m to beyond 6 m: blocks on both sides of the
  // 2 m and 4 m level switches, and blocks whose nearest corner is just past them.
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0.8, 0}, {0, -1, 0}));
  scene.add(sim::makePlane({0, 0, 6.5}, {0.3, 0, -1}));
  MapperConfig config;
  config.histogram_min_points = 0;
  config.voxel_size_m = 0.02;
  ThreadPool pool(2);
  BlockOctree octree(config.blockSizeM());
  BlockLookup lookup(config, &pool);
  SurfaceFuser fuser(config, &pool);
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  size_t compared_blocks = 0, updated_voxels = 0;
  for (int f = 0; f < 3; ++f) {
    T_world_camera.translation() = Eigen::Vector3d(0.05 * f, -0.02 * f, 0.1 * f);
    const StereoFrame frame = renderFrame(scene, vgaCamera(), T_world_camera);
    std::vector<VoxelBlock*> queue, updated;
    lookup.run(frame, &octree, &queue);
    ASSERT_GT(queue.size(), 500u);
    // The reference runs on copies of the blocks as they were before this frame.
    std::vector<VoxelBlock> expected;
    expected.reserve(queue.size());
    for (const VoxelBlock* b : queue) expected.push_back(*b);
    for (VoxelBlock& b : expected) referenceFuseBlock(frame, octree, config, &b);
    fuser.fuse(frame, octree, queue, f + 1, &updated);
    for (size_t n = 0; n < queue.size(); ++n) {
      ++compared_blocks;
      for (size_t v = 0; v < std::size(queue[n]->voxels); ++v) {
        const Voxel& got = queue[n]->voxels[v];
        const Voxel& want = expected[n].voxels[v];
        ASSERT_EQ(std::memcmp(&got, &want, sizeof(Voxel)), 0)
            << "block " << queue[n]->key.x << "," << queue[n]->key.y << "," << queue[n]->key.z << " voxel " << v
            << ": sdf " << got.sdf_m << " vs " << want.sdf_m << ", weight " << got.weight << " vs " << want.weight;
        updated_voxels += want.weight > 0.0f;
      }
    }
  }
  std::printf("[ reference ] %zu block fusions and %zu observed voxels identical\n", compared_blocks, updated_voxels);
}

}  // namespace
}  // namespace stereo_fusion
