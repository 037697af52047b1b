// Free-space carving (FreeSpaceCarver): the rule worked by hand on single voxels, a ghost that
// later frames see through disappears, and what must not be eaten (a thin pole the matcher
// loses in some frames, a floor seen at grazing angles) is not.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "MeshTestSupport.h"
#include "TestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

constexpr double kVoxel = 0.02;

MapperConfig carveConfig(bool carving = true) {
  MapperConfig config;
  config.voxel_size_m = kVoxel;
  config.histogram_min_points = 0;
  config.use_color = false;
  config.mesh_enabled = false;
  config.free_space_carving = carving;
  return config;
}

/// A VGA frame from the identity pose whose every pixel measures depth `depth_m` (f·b = 52.5).
StereoFrame flatFrame(double depth_m) {
  StereoFrame frame;
  frame.camera = vgaCamera();
  frame.T_world_camera = Eigen::Isometry3d::Identity();
  frame.disparity_px = cv::Mat(480, 640, CV_32F, cv::Scalar(52.5 / depth_m));
  return frame;
}

/// Sets voxel (i, j, k) of `level` in `block` and returns the camera point of its centre.
Eigen::Vector3d setVoxel(const BlockOctree& map, VoxelBlock* block, int level, int i, int j, int k,
                         float sdf, float weight) {
  Voxel& v = block->writableAt(level, i, j, k);
  v.sdf_m = sdf;
  v.weight = weight;
  return voxelCentre(map, block->key, level, i, j, k);
}

/// Zero crossings at level 0 along every axis within `radius_m` of `centre`.
size_t crossingsNear(const BlockOctree& map, const Eigen::Vector3d& centre, double radius_m) {
  size_t n = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (const Eigen::Vector3d& p : zeroCrossings(map, 0, axis))
      n += (p - centre).norm() < radius_m;
  return n;
}

}  // namespace

TEST(FreeSpaceCarver, SeenThroughVoxelsAtEveryLevelFadeTowardsMinusPhiHandWorked) {
  const MapperConfig config = carveConfig();
  ThreadPool pool(2);
  BlockOctree map(config.blockSizeM());
  // Block (0, 0, 6) spans z ∈ [0.96, 1.12) m, far in front of a wall measured at 2 m.
  VoxelBlock* block = map.findOrAllocate({0, 0, 6});
  const Eigen::Vector3d p0 = setVoxel(map, block, 0, 3, 3, 3, 0.05f, 10.0f);
  setVoxel(map, block, 2, 1, 1, 1, -0.01f, 4.0f);
  // An unobserved voxel stays unobserved.
  ASSERT_EQ(block->at(0, 5, 5, 5).weight, 0.0f);

  const StereoFrame frame = flatFrame(2.0);
  MeasurementImage measurements;
  measurements.build(frame, stageConfigs(config).pipeline.measurement, &pool);
  FreeSpaceCarver carver(stageConfigs(config).pipeline.carve, &pool);
  std::vector<VoxelBlock*> carved;
  const CarveStats stats = carver.carve(frame, measurements, map, {}, &carved);
  ASSERT_EQ(carved.size(), 1u);
  EXPECT_EQ(stats.voxels_carved, 2u);
  // Depth 2 m is level 0 for this camera (4³ from √(0.02·52.5/0.15) = 2.65 m): Φ = 4 voxels =
  // 0.08 m on level 0, and on level 2 never less than 2 of its 8 cm voxels: 0.16 m.
  // Level 0: W = 10·(1 − 0.2) = 8, then (8·0.05 + 1·(−0.08)) / 9 = 0.035556, W = 9.
  EXPECT_NEAR(block->at(0, 3, 3, 3).sdf_m, (8.0 * 0.05 - 0.08) / 9.0, 1e-6);
  EXPECT_FLOAT_EQ(block->at(0, 3, 3, 3).weight, 9.0f);
  // Level 2: W = 4·0.8 = 3.2, (3.2·(−0.01) + 1·(−0.16)) / 4.2 = −0.045714, W = 4.2.
  EXPECT_NEAR(block->at(2, 1, 1, 1).sdf_m, (3.2 * -0.01 - 0.16) / 4.2, 1e-6);
  EXPECT_FLOAT_EQ(block->at(2, 1, 1, 1).weight, 4.2f);
  EXPECT_EQ(block->at(0, 5, 5, 5).weight, 0.0f);
  EXPECT_EQ(map.blockCount(), 1u) << "carving allocates nothing";
  EXPECT_LT(p0.z(), 1.12);
}

TEST(FreeSpaceCarver, LeavesVoxelsInTheBandBehindTheSurfaceNearAGapAndInFusionsQueue) {
  const MapperConfig config = carveConfig();
  ThreadPool pool(2);
  BlockOctree map(config.blockSizeM());
  // Block (0, 0, 12) spans z ∈ [1.92, 2.08): its voxels lie within 0.08 m of the wall at 2 m
  // (fusion's band) or behind it.
  VoxelBlock* band = map.findOrAllocate({0, 0, 12});
  for (int k = 0; k < 8; ++k) setVoxel(map, band, 0, 2, 2, k, 0.03f, 5.0f);
  // A voxel far in front, whose pixel's 3×3 window holds a pixel without a measurement.
  VoxelBlock* gap = map.findOrAllocate({0, 0, 6});
  const Eigen::Vector3d p = setVoxel(map, gap, 0, 0, 0, 0, 0.04f, 5.0f);
  // A block fusion queued for this frame: fusion writes its free space, not the carver.
  VoxelBlock* queued = map.findOrAllocate({-1, 0, 6});
  setVoxel(map, queued, 0, 4, 4, 4, 0.04f, 5.0f);

  StereoFrame frame = flatFrame(2.0);
  const int u = static_cast<int>(std::floor(525.0 * p.x() / p.z() + 319.5 + 0.5));
  const int v = static_cast<int>(std::floor(525.0 * p.y() / p.z() + 239.5 + 0.5));
  frame.disparity_px.at<float>(v + 1, u - 1) = 0.0f;  // the matcher lost this pixel
  MeasurementImage measurements;
  measurements.build(frame, stageConfigs(config).pipeline.measurement, &pool);
  FreeSpaceCarver carver(stageConfigs(config).pipeline.carve, &pool);
  std::vector<VoxelBlock*> carved;
  carver.carve(frame, measurements, map, {queued}, &carved);
  EXPECT_TRUE(carved.empty());
  for (int k = 0; k < 8; ++k) EXPECT_EQ(band->at(0, 2, 2, k).sdf_m, 0.03f) << k;
  EXPECT_EQ(gap->at(0, 0, 0, 0).sdf_m, 0.04f);
  EXPECT_EQ(queued->at(0, 4, 4, 4).sdf_m, 0.04f);
  EXPECT_EQ(FreeSpaceCarver::freeDepth(measurements.depths(), 640, 480, 1, u, v), 0.0f);
  EXPECT_FLOAT_EQ(FreeSpaceCarver::freeDepth(measurements.depths(), 640, 480, 0, u, v), 2.0f);
  EXPECT_FLOAT_EQ(FreeSpaceCarver::freeDepth(measurements.depths(), 640, 480, 1, u + 3, v), 2.0f);
  // Without the window the gap voxel is carved.
  MapperConfig no_window = config;
  no_window.free_space_window_px = 0;
  FreeSpaceCarver plain(stageConfigs(no_window).pipeline.carve, &pool);
  plain.carve(frame, measurements, map, {queued}, &carved);
  ASSERT_EQ(carved.size(), 1u);
  EXPECT_EQ(carved[0], gap);
}

namespace {

/// A wall at z = 2.5 m; with `ghost`, a sphere (r = 0.2 m) stands in front of it at z = 1.5 m.
sim::AnalyticScene wallWithSphere(bool ghost) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 2.5}, {0, 0, -1}), {200, 170, 120});
  if (ghost) scene.add(sim::makeSphere({0.0, 0.0, 1.5}, 0.2), {90, 90, 200});
  return scene;
}

/// Camera i of a slow sideways sweep looking along +z.
Eigen::Isometry3d sweepView(int i) {
  return lookFrom({-0.3 + 0.02 * i, -0.05, 0.0}, {0.0, 0.0, 2.0});
}

}  // namespace

TEST(FreeSpaceCarver, AGhostThatLaterFramesSeeThroughDisappears) {
  const Eigen::Vector3d sphere_centre(0.0, 0.0, 1.5);
  for (bool carving : {false, true}) {
    MapperConfig config = carveConfig(carving);
    Mapper mapper(config);
    double stamp = 1.0;
    for (int i = 0; i < 30; ++i) {  // the person stands there for 30 frames
      StereoFrame frame = renderFrame(wallWithSphere(true), qvgaCamera(), sweepView(i), 0.1, i);
      frame.timestamp_s = stamp++;
      ASSERT_TRUE(mapper.integrate(frame).accepted);
    }
    const size_t before = crossingsNear(mapper.tsdf(), sphere_centre, 0.3);
    ASSERT_GT(before, 300u);
    for (int i = 0; i < 30; ++i) {  // and then has gone
      StereoFrame frame =
          renderFrame(wallWithSphere(false), qvgaCamera(), sweepView(29 - i), 0.1, 100 + i);
      frame.timestamp_s = stamp++;
      ASSERT_TRUE(mapper.integrate(frame).accepted);
    }
    const size_t after = crossingsNear(mapper.tsdf(), sphere_centre, 0.3);
    std::printf(
        "[ carving %s ] ghost surface crossings: %zu after the first sweep, %zu after the second\n",
        carving ? "on " : "off", before, after);
    if (carving)
      EXPECT_LT(after, before / 20) << "at most 5 % of the ghost may remain";
    else
      EXPECT_GT(after, before / 2)
          << "without carving the ghost stays (else this test shows nothing)";
  }
}

TEST(FreeSpaceCarver, AThinPoleTheMatcherLosesInHalfTheFramesSurvives) {
  // A 2 cm pole before the wall. In every other frame the matcher returns nothing on the pole's
  // pixels, as SGBM does on thin structures: a pixel without a measurement carves nothing, and
  // the window nothing beside it.
  sim::AnalyticScene with_pole = wallWithSphere(false);
  Eigen::Isometry3d T_pole = Eigen::Isometry3d::Identity();
  T_pole.translate(Eigen::Vector3d(0.05, 0.0, 1.4));
  T_pole.rotate(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));  // axis along y
  with_pole.add(sim::makeCylinder(T_pole, 0.01, 0.6), {60, 60, 60});
  const sim::AnalyticScene wall_only = wallWithSphere(false);
  auto poleCrossings = [&](bool carving, int window_px) {
    MapperConfig config = carveConfig(carving);
    config.free_space_window_px = window_px;
    Mapper mapper(config);
    for (int i = 0; i < 30; ++i) {
      StereoFrame frame = renderFrame(with_pole, qvgaCamera(), sweepView(i), 0.1, i);
      frame.timestamp_s = 1.0 + i;
      if (i % 2 == 1) {
        const StereoFrame background = renderFrame(wall_only, qvgaCamera(), sweepView(i));
        const cv::Mat pole = cv::abs(frame.disparity_px - background.disparity_px) > 0.5f;
        frame.disparity_px.setTo(0.0f, pole);
      }
      EXPECT_TRUE(mapper.integrate(frame).accepted);
    }
    size_t n = 0;
    for (int axis = 0; axis < 3; ++axis)
      for (const Eigen::Vector3d& p : zeroCrossings(mapper.tsdf(), 0, axis))
        n += std::hypot(p.x() - 0.05, p.z() - 1.4) < 0.04 && std::abs(p.y()) < 0.4;
    return n;
  };
  const size_t without = poleCrossings(false, 1), with = poleCrossings(true, 1);
  std::printf(
      "[ thin pole ] crossings on the pole: %zu without carving, %zu with (%zu with no window)\n",
      without, with, poleCrossings(true, 0));
  ASSERT_GT(without, 50u);
  EXPECT_GE(with, without * 95 / 100);
}

TEST(FreeSpaceCarver, AFloorSeenAtGrazingAnglesIsNotEaten) {
  // floorAndSphere(): a floor 0.3 m below a camera that steps sideways, disparity noise 0.3 px.
  size_t crossings[2] = {};
  for (bool carving : {false, true}) {
    MapperConfig config = carveConfig(carving);
    Mapper mapper(config);
    for (int i = 0; i < 20; ++i) {
      StereoFrame frame =
          renderFrame(floorAndSphere(), qvgaCamera(), floorAndSphereView(i), 0.3, i);
      frame.timestamp_s = 1.0 + i;
      ASSERT_TRUE(mapper.integrate(frame).accepted);
    }
    size_t n = 0;
    for (const Eigen::Vector3d& p : zeroCrossings(mapper.tsdf(), 0, 1))
      n += std::abs(p.y() - 0.3) < 0.05;
    crossings[carving] = n;
  }
  std::printf("[ grazing floor ] floor crossings: %zu without carving, %zu with\n", crossings[0],
              crossings[1]);
  ASSERT_GT(crossings[0], 1000u);
  EXPECT_GE(crossings[1], crossings[0] * 99 / 100);
}

TEST(FreeSpaceCarver, ResultDoesNotDependOnTheThreadCount) {
  MapSnapshot snapshots[2];
  for (int threads : {1, 2}) {
    MapperConfig config = carveConfig();
    config.num_threads = threads;
    Mapper mapper(config);
    for (int i = 0; i < 10; ++i) {
      StereoFrame frame =
          renderFrame(wallWithSphere(i < 5), qvgaCamera(), sweepView(3 * i), 0.2, i);
      frame.timestamp_s = 1.0 + i;
      ASSERT_TRUE(mapper.integrate(frame).accepted);
    }
    snapshots[threads - 1] = snapshot(mapper.tsdf());
  }
  EXPECT_TRUE(snapshots[0] == snapshots[1]);
}
