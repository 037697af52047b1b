#include <gtest/gtest.h>

#include "TestSupport.h"
#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/planning/FreeSpaceRecorder.h"

namespace stereo_fusion {
namespace {

/// A frame of constant disparity (a wall facing the camera) at identity pose: camera z = world z.
StereoFrame wallFrame(float disparity_px) {
  StereoFrame frame;
  frame.camera = test::vgaCamera();  // f = 525 px, b = 0.1 m: z = 52.5 / d
  frame.disparity_px = cv::Mat(480, 640, CV_32FC1, cv::Scalar(disparity_px));
  return frame;
}

bool seenFree(const std::vector<std::pair<BlockKey, PlanningBlock::Bits>>& blocks,
              const CellIndex& cell) {
  for (const auto& [key, bits] : blocks)
    if (key == planningBlockOf(cell)) return PlanningBlock::test(bits, cellInBlock(cell));
  return false;
}

struct Recorded {
  std::vector<std::pair<BlockKey, PlanningBlock::Bits>> blocks;
  FreeSpaceStats stats;
};

Recorded record(const StereoFrame& frame, double unmeasured_range_m = 0.0) {
  MapperConfig config;  // 2 cm voxels, Φ = 4 voxels of the measurement's level, σ_d 0.15 px
  ThreadPool pool(2);
  MeasurementImage measurements;
  measurements.build(frame, stageConfigs(config).pipeline.measurement, &pool);
  FreeSpaceRecorder recorder({0.08, unmeasured_range_m, config.truncationBand()}, &pool);
  Recorded r;
  r.stats = recorder.record(frame, measurements, &r.blocks);
  return r;
}

// A wall at z = 52.5 / 17.5 = 3 m. Its level: the 4³ level starts at √(0.02 · 52.5 / 0.15) =
// 2.65 m and the 2³ at 3.74 m, so Φ = 4 · 2 · 0.02 = 0.16 m and rays are free up to 2.84 m.
// Hand-worked on the optical axis (cells 8 cm): cell z 34 ([2.72, 2.80)) is free, cell 35
// ([2.80, 2.88)) reaches past 2.84 and is not; behind the wall nothing is; a cell at 0.08 m
// covers more than the image (its footprint is 525 px wide from the centre) and is not free,
// one at 0.40 m is.
TEST(FreeSpaceRecorder, RaysAreFreeUpToTheirDepthMinusTheBandHandWorked) {
  const Recorded r = record(wallFrame(17.5f));
  EXPECT_TRUE(seenFree(r.blocks, {0, 0, 34}));
  EXPECT_TRUE(seenFree(r.blocks, {-1, -1, 34}));
  EXPECT_FALSE(seenFree(r.blocks, {0, 0, 35}));
  EXPECT_FALSE(seenFree(r.blocks, {0, 0, 40}));
  EXPECT_FALSE(seenFree(r.blocks, {0, 0, 1}));
  EXPECT_TRUE(seenFree(r.blocks, {0, 0, 5}));
  // Outside the view at 2 m: x = 2.0 m projects to u = 319.5 + 525 = 844 px.
  EXPECT_FALSE(seenFree(r.blocks, {25, 0, 25}));
  EXPECT_GT(r.stats.cells_seen_free, 10000u);
}

// Pixels without a measurement say nothing (cells seen only through them stay unknown), unless
// free_space_unmeasured_range_m says their rays are empty that far.
TEST(FreeSpaceRecorder, UnmeasuredPixelsSayNothingUnlessARangeIsGiven) {
  StereoFrame frame = wallFrame(17.5f);
  frame.disparity_px(cv::Rect(320, 0, 320, 480)).setTo(0.0f);  // the right half unmatched
  const CellIndex right_of_axis{6, 0, 20};  // x [0.48, 0.56) at z 1.6–1.68 m: u ≥ 477 px
  const CellIndex left_of_axis{-7, 0, 20};
  const Recorded without = record(frame);
  EXPECT_FALSE(seenFree(without.blocks, right_of_axis));
  EXPECT_TRUE(seenFree(without.blocks, left_of_axis));
  const Recorded with = record(frame, 2.0);
  EXPECT_TRUE(seenFree(with.blocks, right_of_axis));
  EXPECT_FALSE(seenFree(with.blocks, {6, 0, 26}));  // beyond the 2 m range
  EXPECT_TRUE(seenFree(with.blocks, left_of_axis));
}

// The recorded cells do not depend on the number of threads.
TEST(FreeSpaceRecorder, ThreadCountIndependent) {
  sim::AnalyticScene scene;
  scene.add(sim::makeSphere(Eigen::Vector3d(0.3, 0.2, 2.0), 0.5));
  scene.add(sim::makePlane(Eigen::Vector3d(0, 0, 4.0), Eigen::Vector3d(0, 0, -1)));
  const StereoFrame frame =
      test::renderFrame(scene, test::vgaCamera(), Eigen::Isometry3d::Identity(), 0.1, 3);
  MapperConfig config;
  std::vector<std::pair<BlockKey, PlanningBlock::Bits>> results[2];
  for (int threads : {1, 2}) {
    ThreadPool pool(threads);
    MeasurementImage measurements;
    measurements.build(frame, stageConfigs(config).pipeline.measurement, &pool);
    FreeSpaceRecorder recorder({0.08, 0.0, config.truncationBand()}, &pool);
    recorder.record(frame, measurements, &results[threads - 1]);
  }
  EXPECT_EQ(results[0], results[1]);
  EXPECT_FALSE(results[0].empty());
}

// Skipping a node that starts past every finest tile's smallest free depth in its footprint
// changes no cell: each of its parts sees one of those tiles. The scene has what makes the skip
// work: a ground seen at a grazing angle out to the far wall, an object's depth edges, noise,
// and a camera turned off the axes; the walk without the skip is the reference.
TEST(FreeSpaceRecorder, SkippingPastTheTilesSmallestFreeDepthsKeepsEveryCell) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane(Eigen::Vector3d(0, 1.2, 0), Eigen::Vector3d(0, -1, 0)));  // ground
  scene.add(sim::makePlane(Eigen::Vector3d(0, 0, 9.0), Eigen::Vector3d(0, 0, -1)));
  scene.add(sim::makeSphere(Eigen::Vector3d(-0.4, 0.6, 3.0), 0.6));
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  T_world_camera.linear() = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  T_world_camera.translation() = Eigen::Vector3d(0.13, -0.05, 0.21);
  const StereoFrame frame = test::renderFrame(scene, test::vgaCamera(), T_world_camera, 0.2, 5);
  MapperConfig config;
  ThreadPool pool(2);
  MeasurementImage measurements;
  measurements.build(frame, stageConfigs(config).pipeline.measurement, &pool);
  std::vector<std::pair<BlockKey, PlanningBlock::Bits>> cells[2];
  FreeSpaceStats stats[2];
  for (int skip : {0, 1}) {
    FreeSpaceRecorder::Params params{0.05, 0.0, config.truncationBand()};
    params.skip_past_tile_minima = skip == 1;
    FreeSpaceRecorder recorder(params, &pool);
    stats[skip] = recorder.record(frame, measurements, &cells[skip]);
  }
  EXPECT_TRUE(cells[1] == cells[0]);  // (printing them would be thousands of words)
  EXPECT_EQ(stats[1].cells_seen_free, stats[0].cells_seen_free);
  EXPECT_GT(stats[0].cells_seen_free, 100000u);
  // The skip is what the test is about: it must cut the walk here.
  EXPECT_LT(stats[1].nodes_visited, stats[0].nodes_visited * 9 / 10);
}

}  // namespace
}  // namespace stereo_fusion
