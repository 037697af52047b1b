// SurfaceFuser against a reference transcription of the thesis equations that visits every
// voxel of every level of every queued block, with none of the fuser's shortcuts (block-level
// depth test, level skipping, depth-tile pre-test); it states the level rule
// (measurementUpdatesLevel()) in its own words. Voxel values must agree bit for bit, so any
// shortcut that drops a real update, or updates what it should not, fails here.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <random>

#include "TestSupport.h"
#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/integration/BlockLookup.h"
#include "stereo_fusion/integration/FusionKernels.h"
#include "stereo_fusion/integration/FusionMath.h"
#include "stereo_fusion/integration/SurfaceFuser.h"

namespace stereo_fusion {
namespace {

using test::renderFrame;
using test::vgaCamera;

/// Eq. 3.8–3.15 for one block, every voxel of every level; the float operations are those of
/// SurfaceFuser so that results are comparable bit for bit. Colour as the fuser: RGB, grey
/// (one channel for all three) or none (empty image or use_color off).
void referenceFuseBlock(const StereoFrame& frame, const BlockOctree& octree,
                        const MapperConfig& config, VoxelBlock* block) {
  const StereoCamera& cam = frame.camera;
  const Eigen::Isometry3d T_camera_world = frame.T_world_camera.inverse();
  const Eigen::Vector3f origin_c = (T_camera_world * octree.blockOrigin(block->key)).cast<float>();
  const Eigen::Matrix3f R_cw = T_camera_world.linear().cast<float>();
  const float fx = static_cast<float>(cam.fx()), fy = static_cast<float>(cam.fy());
  const float cx = static_cast<float>(cam.cx()), cy = static_cast<float>(cam.cy());
  const LevelThresholds thresholds = levelThresholdsFor(
      stageConfigs(config).pipeline.measurement.levels, cam.fx() * cam.baseline());  // the frame's
  const float fb = static_cast<float>(cam.fx() * cam.baseline());
  const float voxel = static_cast<float>(config.voxel_size_m);
  bool allocated_before[kNumLevels];
  for (int level = 0; level < kNumLevels; ++level) allocated_before[level] = block->hasLevel(level);
  for (int level = 0; level < kNumLevels; ++level) {
    const int side = levelSide(level);
    const float level_voxel = voxel * levelScale(level);
    const Eigen::Vector3f ex = R_cw.col(0) * level_voxel, ey = R_cw.col(1) * level_voxel,
                          ez = R_cw.col(2) * level_voxel;
    const Eigen::Vector3f first = origin_c + 0.5f * (ex + ey + ez);
    for (int k = 0; k < side; ++k)
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
          const Eigen::Vector3f p = first + static_cast<float>(i) * ex +
                                    static_cast<float>(j) * ey + static_cast<float>(k) * ez;
          if (!(p.z() > 0.0f)) continue;
          const float u = fx * p.x() / p.z() + cx, v = fy * p.y() / p.z() + cy;
          if (!(u >= -0.5f && v >= -0.5f && u < cam.width() - 0.5f && v < cam.height() - 0.5f))
            continue;
          const int iu = static_cast<int>(std::floor(u + 0.5f)),
                    iv = static_cast<int>(std::floor(v + 0.5f));
          if (iu < 0 || iv < 0 || iu >= cam.width() || iv >= cam.height()) continue;
          const float d = frame.disparity_px.at<float>(iv, iu);
          if (!(d > 0.0f) || !std::isfinite(d)) continue;
          const float z = fb / d;
          if (!(z >= static_cast<float>(config.min_depth_m) &&
                z <= static_cast<float>(config.max_depth_m)))
            continue;
          const int m = levelForDepth(z, thresholds);
          // Its own level and coarser ones; the next finer one too where the block held it.
          const bool finer_held =
              config.update_allocated_finer_level && allocated_before[level] && level == m - 1;
          if (level < m && !finer_held) continue;
          const float scale = static_cast<float>(levelScale(m));
          const float truncation =
              std::max(static_cast<float>(config.truncation_vox) * scale * voxel,
                       TruncationBand::kMinVoxelsOfUpdatedLevel * level_voxel);
          const float delta = static_cast<float>(config.weight_falloff_start_vox) * scale * voxel;
          const float sdf = signedDistanceAlongRay(p.x(), p.y(), p.z(), z);
          if (sdf > truncation) continue;
          const float w = measurementWeight(config.weight_mode, sdf, delta, truncation, z,
                                            static_cast<float>(config.depth_weight_reference_m)) *
                          (finer_held ? 0.25f : 1.0f);
          if (!(w > 0.0f)) continue;
          const uint8_t* rgb = nullptr;
          uint8_t grey[3];
          const bool use_color = config.use_color && !frame.color.empty();
          if (use_color && frame.color.channels() == 3) rgb = frame.color.ptr<uint8_t>(iv) + 3 * iu;
          if (use_color && frame.color.channels() == 1) {
            grey[0] = grey[1] = grey[2] = frame.color.at<uint8_t>(iv, iu);
            rgb = grey;
          }
          Voxel& voxel = block->writableAt(level, i, j, k);
          const float keep =
              config.free_space_carving ? static_cast<float>(1.0 - config.free_space_decay) : 1.0f;
          voxel.weight = weightBeforeUpdate(voxel.sdf_m, voxel.weight, std::max(sdf, -truncation),
                                            truncation, keep);
          fuseMeasurement(&voxel, std::max(sdf, -truncation), w,
                          static_cast<float>(config.max_weight), rgb);
        }
  }
}

/// The kernels under test: the scalar one always, the AVX2 one where the CPU has it.
std::vector<SurfaceFuser::Kernel> kernelsToTest() {
  std::vector<SurfaceFuser::Kernel> kernels{SurfaceFuser::Kernel::kScalar};
  if (avx2Supported()) kernels.push_back(SurfaceFuser::Kernel::kAvx2);
  return kernels;
}

/// Three frames of an analytic scene fused with `kernel`, each block compared with the reference.
void expectFuserEqualsReferenceAcrossAllLevels(SurfaceFuser::Kernel kernel) {
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
  BlockLookup lookup(stageConfigs(config).pipeline.lookup, &pool);
  SurfaceFuser fuser(stageConfigs(config).pipeline.fusion, &pool);
  fuser.setKernel(kernel);
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  size_t compared_blocks = 0, updated_voxels = 0;
  for (int f = 0; f < 3; ++f) {
    T_world_camera.translation() = Eigen::Vector3d(0.05 * f, -0.02 * f, 0.1 * f);
    const StereoFrame frame = renderFrame(scene, vgaCamera(), T_world_camera);
    std::vector<VoxelBlock*> queue, updated;
    MeasurementImage measurements;
    measurements.build(frame, stageConfigs(config).pipeline.measurement, &pool);
    lookup.run(frame, measurements, &octree, &queue);
    ASSERT_GT(queue.size(), 500u);
    // The reference runs on copies of the blocks as they were before this frame.
    std::vector<VoxelBlock> expected;
    expected.reserve(queue.size());
    for (const VoxelBlock* b : queue) expected.push_back(*b);
    for (VoxelBlock& b : expected) referenceFuseBlock(frame, octree, config, &b);
    fuser.fuse(frame, measurements, octree, queue, &updated);
    for (size_t n = 0; n < queue.size(); ++n) {
      ++compared_blocks;
      for (int level = 0; level < kNumLevels; ++level)
        ASSERT_EQ(queue[n]->hasLevel(level), expected[n].hasLevel(level))
            << "level " << level << " allocated";
      for (int v = 0; v < VoxelBlock::kVoxelCount; ++v) {
        const Voxel& got = queue[n]->voxel(v);
        const Voxel& want = expected[n].voxel(v);
        ASSERT_EQ(std::memcmp(&got, &want, sizeof(Voxel)), 0)
            << "block " << queue[n]->key.x << "," << queue[n]->key.y << "," << queue[n]->key.z
            << " voxel " << v << ": sdf " << got.sdf_m << " vs " << want.sdf_m << ", weight "
            << got.weight << " vs " << want.weight;
        updated_voxels += want.weight > 0.0f;
      }
    }
  }
  std::printf("[ reference ] %zu block fusions and %zu observed voxels identical\n",
              compared_blocks, updated_voxels);
}

TEST(FusionReference, FuserEqualsPerVoxelReferenceAcrossAllLevels) {
  for (SurfaceFuser::Kernel kernel : kernelsToTest()) {
    SCOPED_TRACE(kernel == SurfaceFuser::Kernel::kAvx2 ? "AVX2 kernel" : "scalar kernel");
    expectFuserEqualsReferenceAcrossAllLevels(kernel);
  }
}

/// A disparity image of a random plane in front of the camera, with every kind of value the
/// fuser must reject (0, negative, NaN, ±inf, denormal, huge) sprinkled in, and tiny
/// disparities whose depths fall beyond any range. `plane_seed` picks the plane, so frames of
/// one trial can share it.
cv::Mat randomDisparity(const StereoCamera& cam, uint32_t plane_seed, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::mt19937 plane_rng(plane_seed);
  const Eigen::Vector3d normal =
      Eigen::Vector3d(unit(plane_rng) - 0.5, unit(plane_rng) - 0.5, -1.0).normalized();
  const double plane_depth_m = 0.3 + 6.0 * unit(plane_rng);  // along the optical axis
  const float special[] = {0.0f,
                           -1.0f,
                           std::numeric_limits<float>::quiet_NaN(),
                           std::numeric_limits<float>::infinity(),
                           -std::numeric_limits<float>::infinity(),
                           std::numeric_limits<float>::denorm_min(),
                           1e-30f,
                           1e30f,
                           1e-3f};
  cv::Mat disparity(cam.height(), cam.width(), CV_32FC1);
  for (int v = 0; v < cam.height(); ++v)
    for (int u = 0; u < cam.width(); ++u) {
      float& d = disparity.at<float>(v, u);
      if (unit(*rng) < 0.1) {
        d = special[(*rng)() % std::size(special)];
        continue;
      }
      const Eigen::Vector3d ray((u - cam.cx()) / cam.fx(), (v - cam.cy()) / cam.fy(), 1.0);
      const double along = plane_depth_m * normal.z() / normal.dot(ray);  // depth of the ray's hit
      const double z = along > 0 ? along * (1.0 + 0.02 * (unit(*rng) - 0.5)) : 50.0;
      d = static_cast<float>(cam.fx() * cam.baseline() / z);
    }
  return disparity;
}

/// Keys of blocks around the surface seen by random pixels (and a few anywhere, including
/// behind the camera and outside the image), without repeats.
std::vector<BlockKey> randomBlockKeys(const StereoFrame& frame, const BlockOctree& octree,
                                      std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const StereoCamera& cam = frame.camera;
  std::vector<BlockKey> keys;
  for (int n = 0; n < 160; ++n) {
    // Pixels slightly beyond the borders too, so blocks straddle them.
    const double u = -3.0 + (cam.width() + 6.0) * unit(*rng),
                 v = -3.0 + (cam.height() + 6.0) * unit(*rng);
    const int iu = std::clamp(static_cast<int>(u), 0, cam.width() - 1);
    const int iv = std::clamp(static_cast<int>(v), 0, cam.height() - 1);
    const float d = frame.disparity_px.at<float>(iv, iu);
    double z = (d > 0 && std::isfinite(d)) ? cam.fx() * cam.baseline() / d : 3.0;
    if (n % 8 == 0) z = -1.0 + 10.0 * unit(*rng);  // anywhere, also behind the camera
    z = std::min(z, 12.0) + 0.3 * (unit(*rng) - 0.5);
    const Eigen::Vector3d p_c((u - cam.cx()) / cam.fx() * z, (v - cam.cy()) / cam.fy() * z, z);
    const BlockKey key = octree.keyForPoint(frame.T_world_camera * p_c);
    if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
  }
  return keys;
}

/// Voxels as a map may hold them: some never observed, some with random history.
void randomizeVoxels(VoxelBlock* block, float max_weight, std::mt19937* rng) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  if (unit(*rng) < 0.3f) return;
  for (int n = 0; n < VoxelBlock::kVoxelCount; ++n) {
    if (unit(*rng) < 0.3f) continue;
    Voxel& voxel = block->writableVoxel(n);
    voxel.weight = max_weight * unit(*rng);
    voxel.sdf_m = 0.2f * (unit(*rng) - 0.5f);
    voxel.r = static_cast<uint8_t>((*rng)());
    voxel.g = static_cast<uint8_t>((*rng)());
    voxel.b = static_cast<uint8_t>((*rng)());
    voxel.reserved = static_cast<uint8_t>((*rng)());  // never written by fusion: must survive
  }
}

TEST(FusionReference, KernelsEqualReferenceOnRandomFramesAndBlocks) {
  // Random image sizes (not multiples of 8, single rows and columns), poses, colour kinds,
  // weight modes and level thresholds that are no float (2.0000001 m): every kernel must
  // produce the reference's voxels bit for bit and the same update counts.
  std::mt19937 rng(20261122);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int widths[] = {640, 641, 37, 9, 1, 203};
  const int heights[] = {480, 13, 1, 77};
  const double voxel_sizes[] = {0.01, 0.02, 0.035, 0.05};
  const WeightMode modes[] = {WeightMode::kConstant, WeightMode::kSteinbruecker,
                              WeightMode::kDepthAware};
  ThreadPool pool(2);
  size_t compared_voxels = 0, updates = 0;
  for (int trial = 0; trial < 48; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    MapperConfig config;
    config.voxel_size_m = voxel_sizes[rng() % std::size(voxel_sizes)];
    config.truncation_vox = 1.0 + 5.0 * unit(rng);
    config.weight_falloff_start_vox = 0.5 + 1.5 * unit(rng);
    config.weight_mode = modes[rng() % std::size(modes)];
    config.depth_weight_reference_m = 0.5 + unit(rng);
    config.max_weight = rng() % 2 ? 100.0 : 3.0;
    config.min_depth_m = rng() % 2 ? 0.1 : 0.0;
    config.max_depth_m = rng() % 2 ? 8.0 : 1e30;
    config.level_mode = LevelMode::kDepth;  // the thresholds below, drawn at random
    config.levels.scale2_min_depth_m = rng() % 2 ? 2.0 : 2.0000001;
    config.levels.scale4_min_depth_m =
        rng() % 2 ? 4.0 : 1.0 + 5.0 * unit(rng);  // may be below level 1's
    config.use_color = rng() % 4 != 0;
    config.update_allocated_finer_level = trial % 4 != 0;
    const int width = widths[rng() % std::size(widths)],
              height = heights[rng() % std::size(heights)];
    const double f_px = 30.0 + 800.0 * unit(rng);
    const StereoCamera cam = *StereoCamera::create(
        width, height, f_px, f_px * (0.9 + 0.2 * unit(rng)), (width - 1) / 2.0 + unit(rng),
        (height - 1) / 2.0 - unit(rng), 0.05 + 0.2 * unit(rng));
    BlockOctree octree(config.blockSizeM());
    std::vector<SurfaceFuser> fusers;
    for (SurfaceFuser::Kernel kernel : kernelsToTest()) {
      fusers.emplace_back(stageConfigs(config).pipeline.fusion, &pool);
      fusers.back().setKernel(kernel);
    }
    std::vector<std::vector<VoxelBlock>> blocks(fusers.size());
    std::vector<VoxelBlock> expected;
    const uint32_t plane_seed = rng();
    Eigen::Isometry3d T_world_first = Eigen::Isometry3d::Identity();
    for (int frame_index = 1; frame_index <= 2; ++frame_index) {
      StereoFrame frame;
      frame.camera = cam;
      frame.disparity_px = randomDisparity(cam, plane_seed, &rng);
      const int color_kind = static_cast<int>(rng() % 3);
      if (color_kind != 2) {
        frame.color.create(height, width, color_kind == 0 ? CV_8UC3 : CV_8UC1);
        for (int v = 0; v < height; ++v)
          for (size_t byte = 0; byte < frame.color.step[0]; ++byte)
            frame.color.ptr<uint8_t>(v)[byte] = static_cast<uint8_t>(rng());
      }
      // The first pose anywhere; the second a few centimetres and degrees from it, so that it
      // sees the same blocks again and averages into observed voxels.
      std::normal_distribution<double> gauss;
      const double spread = frame_index == 1 ? 1.0 : 0.03;
      const Eigen::Quaterniond q =
          Eigen::Quaterniond(frame_index == 1 ? gauss(rng) : 1.0, spread * gauss(rng),
                             spread * gauss(rng), spread * gauss(rng))
              .normalized();
      Eigen::Isometry3d T_first_camera = Eigen::Isometry3d::Identity();
      T_first_camera.linear() = q.toRotationMatrix();
      T_first_camera.translation() =
          Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)) * (frame_index == 1 ? 10.0 : spread);
      frame.T_world_camera = T_world_first * T_first_camera;
      if (frame_index == 1) {
        T_world_first = frame.T_world_camera;
        // Blocks chosen from the first frame; the second frame sees them from elsewhere.
        for (const BlockKey& key : randomBlockKeys(frame, octree, &rng)) {
          expected.emplace_back();
          expected.back().key = key;
          randomizeVoxels(&expected.back(), static_cast<float>(config.max_weight), &rng);
        }
        for (auto& copy : blocks) copy = expected;
      }
      for (VoxelBlock& b : expected) referenceFuseBlock(frame, octree, config, &b);
      std::vector<uint64_t> voxels_updated;
      MeasurementImage measurements;
      measurements.build(frame, stageConfigs(config).pipeline.measurement, &pool);
      for (size_t n = 0; n < fusers.size(); ++n) {
        std::vector<VoxelBlock*> queue, updated;
        for (VoxelBlock& b : blocks[n]) queue.push_back(&b);
        voxels_updated.push_back(
            fusers[n].fuse(frame, measurements, octree, queue, &updated).voxels_updated);
      }
      for (size_t n = 1; n < fusers.size(); ++n) EXPECT_EQ(voxels_updated[n], voxels_updated[0]);
      updates += voxels_updated[0];
      for (size_t n = 0; n < fusers.size(); ++n)
        for (size_t b = 0; b < expected.size(); ++b)
          for (int v = 0; v < VoxelBlock::kVoxelCount; ++v) {
            if (v == 0) {
              for (int level = 0; level < kNumLevels; ++level)
                ASSERT_EQ(blocks[n][b].hasLevel(level), expected[b].hasLevel(level))
                    << "kernel " << n << " level " << level;
            }
            const Voxel& got = blocks[n][b].voxel(v);
            const Voxel& want = expected[b].voxel(v);
            ASSERT_EQ(std::memcmp(&got, &want, sizeof(Voxel)), 0)
                << "kernel " << n << " block " << b << " voxel " << v << ": sdf " << got.sdf_m
                << " vs " << want.sdf_m << ", weight " << got.weight << " vs " << want.weight;
            ++compared_voxels;
          }
    }
  }
  std::printf("[ kernels ] %zu voxels identical over %zu kernels, %zu updates\n", compared_voxels,
              kernelsToTest().size(), updates);
  EXPECT_GT(updates, 10000u);
}

}  // namespace
}  // namespace stereo_fusion
