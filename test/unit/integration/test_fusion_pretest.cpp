// The AVX2 kernel skips whole groups of voxels (a level of a block, a k-slice) when the
// frame's DepthTiles prove that none of them can be updated. These tests check the tiles
// against a per-pixel transcription of their rule, and put voxels right at the limits of the
// proof (the band Φ behind the surface, the image borders, the level thresholds), holding the
// AVX2 kernel against the scalar one, which has no pre-test: a pre-test that skipped a single
// voxel it should not have fails here.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/integration/DepthTiles.h"
#include "stereo_fusion/integration/FusionKernels.h"
#include "stereo_fusion/integration/SurfaceFuser.h"

namespace stereo_fusion {
namespace {

/// The largest depth among pixels [u0, u1) × [v0, v1) whose measurement level is at most
/// `max_level` (levelForDepth() with float thresholds); −inf if none.
float bruteForceMax(const std::vector<float>& depth_m, int width, int u0, int v0, int u1, int v1,
                    float t1, float t2, int max_level = 0) {
  float max_m = -std::numeric_limits<float>::infinity();
  for (int v = v0; v < v1; ++v)
    for (int u = u0; u < u1; ++u) {
      const float z = depth_m[static_cast<size_t>(v) * width + u];
      if (std::isnan(z)) continue;
      const int m = z >= t2 ? 2 : (z >= t1 ? 1 : 0);
      if (m <= max_level) max_m = std::max(max_m, z);
    }
  return max_m;
}

TEST(DepthTiles, MaxDepthFollowsThePerPixelRule) {
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
      const float special[] = {t1,
                               std::nextafter(t1, 0.0f),
                               t2,
                               std::nextafter(t2, 0.0f),
                               std::numeric_limits<float>::quiet_NaN(),
                               0.1f,
                               7.9f};
      std::vector<float> depth_m(static_cast<size_t>(width) * height);
      for (float& z : depth_m)
        z = unit(rng) < 0.3f ? special[rng() % std::size(special)] : 0.1f + 6.0f * unit(rng);
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
      using Which = DepthTiles::Measurements;
      for (const auto [which, max_level] :
           {std::pair{Which::kLevel0, 0}, std::pair{Which::kLevel0And1, 1}}) {
        for (int ty = 0; ty < tiles.tilesY(); ++ty)
          for (int tx = 0; tx < tiles.tilesX(); ++tx) {
            const float want =
                bruteForceMax(depth_m, width, 8 * tx, 8 * ty, std::min(8 * tx + 8, width),
                              std::min(8 * ty + 8, height), t1, t2, max_level);
            ASSERT_EQ(tiles.maxDepth(which, tx, ty, tx, ty), want)
                << width << "x" << height << " tile " << tx << "," << ty
                << " levels <= " << max_level;
            EXPECT_EQ(tiles.allBelow(which, tx, ty, tx, ty, std::nextafter(want, INFINITY)), true);
            EXPECT_EQ(tiles.allBelow(which, tx, ty, tx, ty, want), false);
          }
        // A query over several tiles is the maximum over their pixels.
        const float want = bruteForceMax(depth_m, width, 0, 0, width, height, t1, t2, max_level);
        EXPECT_EQ(tiles.maxDepth(which, 0, 0, tiles.tilesX() - 1, tiles.tilesY() - 1), want);
      }
    }
  }
  // The summaries differ where they should: a tile of level-1 depths has none of level 0.
  std::vector<float> depth_m(64, 3.0f);
  DepthTiles tiles;
  tiles.build(depth_m.data(), 8, 8, 2.0f, 4.0f, &pool);
  EXPECT_EQ(tiles.maxDepth(DepthTiles::Measurements::kLevel0, 0, 0, 0, 0), -INFINITY);
  EXPECT_EQ(tiles.maxDepth(DepthTiles::Measurements::kLevel0And1, 0, 0, 0, 0), 3.0f);
}

/// A small camera (fast to fuse thousands of times) whose 8-pixel tiles each cover a few
/// voxels of a block 1.5 m away.
StereoCamera smallCamera() { return *StereoCamera::create(96, 72, 300.0, 310.0, 47.3, 35.6, 0.1); }

/// A frame seeing one surface at `depth_m` everywhere (a fronto-parallel plane).
StereoFrame planeFrame(const StereoCamera& cam, const Eigen::Isometry3d& T_world_camera,
                       float disparity_px) {
  StereoFrame frame;
  frame.camera = cam;
  frame.T_world_camera = T_world_camera;
  frame.disparity_px = cv::Mat(cam.height(), cam.width(), CV_32FC1, cv::Scalar(disparity_px));
  return frame;
}

float disparityForDepth(const StereoCamera& cam, double depth_m) {
  return static_cast<float>(cam.fx() * cam.baseline() / depth_m);
}

/// Runs the scalar kernel (no pre-test) and the AVX2 kernel (with it) on fresh copies of block
/// `key`; expects identical voxels and update counts. Returns the number of updates.
class KernelPair {
 public:
  explicit KernelPair(const MapperConfig& config)
      : config_(config),
        octree_(config.blockSizeM()),
        scalar_(stageConfigs(config).pipeline.fusion, &pool_),
        avx2_(stageConfigs(config).pipeline.fusion, &pool_) {
    scalar_.setKernel(SurfaceFuser::Kernel::kScalar);
    if (avx2Supported()) avx2_.setKernel(SurfaceFuser::Kernel::kAvx2);
  }

  const BlockOctree& octree() const { return octree_; }

  /// `held_levels`: bit l set allocates level l of both blocks (all unobserved) before fusion,
  /// as nearer views would have, so measurements of level l + 1 update it too
  /// (measurementUpdatesLevel()).
  uint64_t expectAgree(const StereoFrame& frame, const BlockKey& key, int held_levels = 0) {
    VoxelBlock want, got;
    want.key = got.key = key;
    for (int level = 0; level < kNumLevels; ++level)
      if (held_levels & (1 << level)) {
        want.writableLevel(level);
        got.writableLevel(level);
      }
    std::vector<VoxelBlock*> updated;
    MeasurementImage measurements;
    measurements.build(frame, stageConfigs(config_).pipeline.measurement, &pool_);
    const uint64_t want_updates =
        scalar_.fuse(frame, measurements, octree_, {&want}, &updated).voxels_updated;
    const uint64_t got_updates =
        avx2_.fuse(frame, measurements, octree_, {&got}, &updated).voxels_updated;
    EXPECT_EQ(got_updates, want_updates);
    for (int level = 0; level < kNumLevels; ++level)
      EXPECT_EQ(got.hasLevel(level), want.hasLevel(level)) << "level " << level << " allocated";
    for (int v = 0; v < VoxelBlock::kVoxelCount; ++v)
      if (std::memcmp(&got.voxel(v), &want.voxel(v), sizeof(Voxel)) != 0) {
        ADD_FAILURE() << "voxel " << v << ": weight " << got.voxel(v).weight << " vs "
                      << want.voxel(v).weight;
        break;
      }
    level0_observed_ = 0;
    if (want.hasLevel(0))
      for (int v = 0; v < levelVoxelCount(0); ++v)
        level0_observed_ += want.level(0)[v].weight > 0.0f;
    return want_updates;
  }

  /// Observed level-0 voxels after the last expectAgree().
  int level0Observed() const { return level0_observed_; }

 private:
  MapperConfig config_;
  int level0_observed_ = 0;
  ThreadPool pool_{1};
  BlockOctree octree_;
  SurfaceFuser scalar_, avx2_;
};

/// Camera poses: looking along the world z axis, and turned so that no block axis is aligned
/// with the camera's.
std::vector<Eigen::Isometry3d> testPoses() {
  Eigen::Isometry3d turned = Eigen::Isometry3d::Identity();
  turned.linear() = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitX()) *
                     Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()))
                        .toRotationMatrix();
  turned.translation() = Eigen::Vector3d(0.013, -0.007, 0.004);
  return {Eigen::Isometry3d::Identity(), turned};
}

TEST(FusionPreTest, NeverSkipsVoxelsAtTheBackOfTheBand) {
  // The surface sweeps through z_c − Φ of every slice and level of a block: each voxel goes
  // from "behind by more than Φ" (not updated) to updated, a few µm either side of its
  // boundary, where the pre-test's margin must keep it.
  if (!avx2Supported()) GTEST_SKIP() << "no AVX2 kernel on this CPU";
  MapperConfig config;
  KernelPair kernels(config);
  const StereoCamera cam = smallCamera();
  uint64_t total_updates = 0;
  int sweeps_with_partial_updates = 0;
  for (const Eigen::Isometry3d& T_world_camera : testPoses()) {
    const BlockKey key =
        kernels.octree().keyForPoint(T_world_camera * Eigen::Vector3d(0.12, -0.05, 1.5));
    const Eigen::Isometry3d T_camera_world = T_world_camera.inverse();
    const double voxel_m = config.voxel_size_m;
    for (int level = 0; level < kNumLevels; ++level) {
      const double level_voxel_m = voxel_m * levelScale(level);
      const double truncation_m = config.truncationBand().updateM(0, level);
      for (int k = 0; k < levelSide(level); ++k) {
        // Depth of the slice's nearest voxel centre (the pre-test bounds by the nearest).
        double z_near_m = INFINITY;
        for (int c = 0; c < 4; ++c) {
          const Eigen::Vector3d centre =
              kernels.octree().blockOrigin(key) +
              level_voxel_m * Eigen::Vector3d((c & 1) * (levelSide(level) - 1) + 0.5,
                                              (c >> 1) * (levelSide(level) - 1) + 0.5, k + 0.5);
          z_near_m = std::min(z_near_m, (T_camera_world * centre).z());
        }
        uint64_t previous = 0;
        bool partial = false;
        for (double offset_m :
             {-2e-3, -3e-4, -1e-4, -3e-5, -1e-5, -1e-6, 0.0, 1e-6, 1e-5, 3e-5, 1e-4, 3e-4, 2e-3}) {
          const double surface_m = z_near_m - truncation_m + offset_m;
          const uint64_t updates = kernels.expectAgree(
              planeFrame(cam, T_world_camera, disparityForDepth(cam, surface_m)), key);
          partial |= updates != previous && previous != 0;
          previous = updates;
          total_updates += updates;
        }
        sweeps_with_partial_updates += partial;
        if (HasFailure()) return;
      }
    }
  }
  EXPECT_GT(total_updates, 1000u);
  EXPECT_GT(sweeps_with_partial_updates, 0);  // the sweeps do cross voxel boundaries
}

TEST(FusionPreTest, NeverSkipsVoxelsAtTheImageBorders) {
  // A block slides across each image border in steps of a fifth of a pixel, with the surface
  // through its middle: its columns and rows leave the image one by one.
  if (!avx2Supported()) GTEST_SKIP() << "no AVX2 kernel on this CPU";
  MapperConfig config;
  KernelPair kernels(config);
  const StereoCamera cam = smallCamera();
  const double depth_m = 1.5, block_m = config.blockSizeM();
  uint64_t total_updates = 0;
  for (const Eigen::Isometry3d& T_world_camera : testPoses()) {
    // Corners of the image as rays at 1.5 m; the block starts fully inside and ends outside.
    const Eigen::Vector2d borders_px[] = {{-0.5, cam.cy()},
                                          {cam.width() - 0.5, cam.cy()},
                                          {cam.cx(), -0.5},
                                          {cam.cx(), cam.height() - 0.5}};
    for (const Eigen::Vector2d& border : borders_px) {
      const Eigen::Vector3d on_border((border.x() - cam.cx()) / cam.fx() * depth_m,
                                      (border.y() - cam.cy()) / cam.fy() * depth_m, depth_m);
      const Eigen::Vector3d outward =
          Eigen::Vector3d(border.x() - cam.cx(), border.y() - cam.cy(), 0).normalized();
      const double step_m = 0.2 * depth_m / cam.fx();
      for (double shift_m = -1.5 * block_m; shift_m <= 1.5 * block_m; shift_m += step_m) {
        const Eigen::Vector3d centre_c = on_border + shift_m * outward;
        const BlockKey key = kernels.octree().keyForPoint(T_world_camera * centre_c);
        total_updates += kernels.expectAgree(
            planeFrame(cam, T_world_camera, disparityForDepth(cam, depth_m)), key);
        if (HasFailure()) return;
      }
    }
  }
  EXPECT_GT(total_updates, 1000u);
}

TEST(FusionPreTest, NeverSkipsAtTheLevelThresholds) {
  // Surfaces on consecutive floats around the level switches at 2 m and 4 m, seen by blocks
  // straddling them: a measurement one ulp nearer than a threshold still updates the finer
  // level, one at the threshold does not.
  if (!avx2Supported()) GTEST_SKIP() << "no AVX2 kernel on this CPU";
  MapperConfig config;
  KernelPair kernels(config);
  const StereoCamera cam = smallCamera();
  uint64_t total_updates = 0;
  for (const Eigen::Isometry3d& T_world_camera : testPoses()) {
    for (double threshold_m :
         {config.levels.scale2_min_depth_m, config.levels.scale4_min_depth_m}) {
      for (double block_offset_m : {-0.1, -0.03, 0.0, 0.03, 0.1}) {
        const BlockKey key = kernels.octree().keyForPoint(
            T_world_camera * Eigen::Vector3d(0.05, 0.02, threshold_m + block_offset_m));
        float disparity = disparityForDepth(cam, threshold_m);
        for (int n = 0; n < 6; ++n) disparity = std::nextafter(disparity, INFINITY);
        for (int n = 0; n < 12; ++n, disparity = std::nextafter(disparity, 0.0f))
          total_updates += kernels.expectAgree(planeFrame(cam, T_world_camera, disparity), key);
        if (HasFailure()) return;
      }
    }
  }
  EXPECT_GT(total_updates, 1000u);
}

TEST(FusionPreTest, NeverSkipsAHeldFinerLevelUpdatedByCoarserMeasurements) {
  // A block that holds level 0 gets level-1 measurements (the 4³ switch at 1 m, the block at
  // 1.5 m): they update its level-0 voxels with their own band Φ₁ = updateM(1, 0), so the
  // pre-test must use the level-0-and-1 tiles and that band. The surface sweeps through
  // z_c − Φ₁ of every level-0 slice; the same without the held level updates no level-0 voxel.
  if (!avx2Supported()) GTEST_SKIP() << "no AVX2 kernel on this CPU";
  MapperConfig config;
  config.level_mode = LevelMode::kDepth;
  config.levels.scale2_min_depth_m = 1.0;
  config.levels.scale4_min_depth_m = 4.0;
  ASSERT_TRUE(config.update_allocated_finer_level);
  KernelPair kernels(config);
  const StereoCamera cam = smallCamera();
  const double truncation_m = config.truncationBand().updateM(1, 0);
  int sweeps_with_partial_updates = 0, level0_observed = 0;
  for (const Eigen::Isometry3d& T_world_camera : testPoses()) {
    const BlockKey key =
        kernels.octree().keyForPoint(T_world_camera * Eigen::Vector3d(0.12, -0.05, 1.5));
    const Eigen::Isometry3d T_camera_world = T_world_camera.inverse();
    for (int k = 0; k < levelSide(0); ++k) {
      double z_near_m = INFINITY;
      for (int c = 0; c < 4; ++c) {
        const Eigen::Vector3d centre =
            kernels.octree().blockOrigin(key) +
            config.voxel_size_m * Eigen::Vector3d((c & 1) * (levelSide(0) - 1) + 0.5,
                                                  (c >> 1) * (levelSide(0) - 1) + 0.5, k + 0.5);
        z_near_m = std::min(z_near_m, (T_camera_world * centre).z());
      }
      int previous = 0;
      bool partial = false;
      for (double offset_m : {-2e-3, -1e-4, -1e-5, -1e-6, 0.0, 1e-6, 1e-5, 1e-4, 2e-3}) {
        const StereoFrame frame = planeFrame(
            cam, T_world_camera, disparityForDepth(cam, z_near_m - truncation_m + offset_m));
        kernels.expectAgree(frame, key, /*held_levels=*/0b001);
        const int observed = kernels.level0Observed();
        partial |= observed != previous && previous != 0;
        previous = observed;
        level0_observed += observed;
        kernels.expectAgree(frame, key, /*held_levels=*/0);
        EXPECT_EQ(kernels.level0Observed(), 0)
            << "level 0 is not held: no level-1 measurement allocates it";
      }
      sweeps_with_partial_updates += partial;
      if (HasFailure()) return;
    }
  }
  EXPECT_GT(level0_observed, 1000);
  EXPECT_GT(sweeps_with_partial_updates, 0);
}

TEST(FusionPreTest, NeverSkipsAtTheLevelThresholdsWithHeldFinerLevels) {
  // NeverSkipsAtTheLevelThresholds with levels 0 and 1 held: a measurement one ulp beyond a
  // threshold now updates the finer level too.
  if (!avx2Supported()) GTEST_SKIP() << "no AVX2 kernel on this CPU";
  MapperConfig config;
  config.level_mode = LevelMode::kDepth;
  KernelPair kernels(config);
  const StereoCamera cam = smallCamera();
  uint64_t total_updates = 0;
  for (const Eigen::Isometry3d& T_world_camera : testPoses()) {
    for (double threshold_m :
         {config.levels.scale2_min_depth_m, config.levels.scale4_min_depth_m}) {
      for (double block_offset_m : {-0.1, 0.0, 0.1}) {
        const BlockKey key = kernels.octree().keyForPoint(
            T_world_camera * Eigen::Vector3d(0.05, 0.02, threshold_m + block_offset_m));
        float disparity = disparityForDepth(cam, threshold_m);
        for (int n = 0; n < 4; ++n) disparity = std::nextafter(disparity, INFINITY);
        for (int n = 0; n < 8; ++n, disparity = std::nextafter(disparity, 0.0f))
          total_updates +=
              kernels.expectAgree(planeFrame(cam, T_world_camera, disparity), key, 0b011);
        if (HasFailure()) return;
      }
    }
  }
  EXPECT_GT(total_updates, 1000u);
}

}  // namespace
}  // namespace stereo_fusion
