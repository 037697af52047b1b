// The planning layer on analytic scenes with known distances, under eviction, and queried from
// another thread while frames are fused.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <thread>

#include "QuickMode.h"
#include "PlanningSceneSupport.h"
#include "TestSupport.h"
#include "stereo_fusion/Mapper.h"

namespace stereo_fusion {
namespace {

using test::renderFrame;
using test::vgaCamera;

using test::planningSceneConfig;

// A 4 cm thin wall (a box) at x = 2 m seen from x = 0: cells in front read their distance to
// it within a cell diagonal, cells behind it stay unknown, and the wall itself is occupied.
TEST(PlanningScenes, ThinWallDistancesInFrontAndUnknownBehind) {
  sim::AnalyticScene scene;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(2.02, 0.0, 1.0);
  scene.add(sim::makeBox(T, Eigen::Vector3d(0.02, 2.0, 1.0)));
  Mapper mapper(planningSceneConfig());
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d eye(0.0, -0.2 + 0.2 * i, 1.0);
    StereoFrame frame =
        renderFrame(scene, vgaCamera(), sim::lookAt(eye, eye + Eigen::Vector3d::UnitX()));
    frame.timestamp_s = 1.0 + i;
    ASSERT_TRUE(mapper.integrate(frame).accepted);
  }
  mapper.updatePlanning();
  const PlanningMap& planning = *mapper.planning();
  const double cell_m = planning.config().cell_m, diagonal = std::sqrt(3.0) * cell_m;
  for (double x : {0.6, 1.0, 1.4, 1.8}) {
    const Eigen::Vector3d p(x, 0.1, 1.0);
    const EsdfSample s = planning.sample(p);
    ASSERT_EQ(s.state, CellState::kFree) << x;
    // Cell centres against the wall's face at x = 2.0: within a cell diagonal.
    CellIndex cell;
    ASSERT_TRUE(planning.grid().cellFor(p, &cell));
    const Eigen::Vector3d centre = planning.grid().centre(cell);
    EXPECT_NEAR(s.distance_m, 2.0 - centre.x(), diagonal) << x;
  }
  EXPECT_EQ(planning.state({2.02, 0.1, 1.0}), CellState::kOccupied);
  EXPECT_EQ(planning.state({2.5, 0.1, 1.0}), CellState::kUnknown);
  EXPECT_EQ(planning.state({3.0, 0.1, 1.0}), CellState::kUnknown);
}

// A corridor 1.2 m wide (walls at y = ±0.6 m, floor, ceiling, an end wall at x = 5 m) seen
// along its axis: on the axis the distance is the half-width, the gradient points across; cells
// near a wall read less.
TEST(PlanningScenes, CorridorHalfWidthOnTheAxis) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane(Eigen::Vector3d(0, 0.6, 0), Eigen::Vector3d(0, -1, 0)));
  scene.add(sim::makePlane(Eigen::Vector3d(0, -0.6, 0), Eigen::Vector3d(0, 1, 0)));
  scene.add(sim::makePlane(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 1)));
  scene.add(sim::makePlane(Eigen::Vector3d(0, 0, 2.0), Eigen::Vector3d(0, 0, -1)));
  scene.add(sim::makePlane(Eigen::Vector3d(5.0, 0, 0), Eigen::Vector3d(-1, 0, 0)));
  Mapper mapper(planningSceneConfig());
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector3d eye(0.3 * i, 0.0, 1.0);
    const double yaw = (i % 2 ? 1 : -1) * 0.5;
    StereoFrame frame =
        renderFrame(scene, vgaCamera(),
                    sim::lookAt(eye, eye + Eigen::Vector3d(std::cos(yaw), std::sin(yaw), -0.1)));
    frame.timestamp_s = 1.0 + i;
    ASSERT_TRUE(mapper.integrate(frame).accepted);
  }
  mapper.updatePlanning();
  const PlanningMap& planning = *mapper.planning();
  const double cell_m = planning.config().cell_m;
  const EsdfSample axis = planning.sample({2.5, 0.04, 1.0});  // a cell centre on the axis: y 0.04
  ASSERT_EQ(axis.state, CellState::kFree);
  EXPECT_NEAR(axis.distance_m, 0.6, std::sqrt(3.0) * cell_m);
  const EsdfSample near_wall = planning.sample({2.5, 0.44, 1.0});
  ASSERT_EQ(near_wall.state, CellState::kFree);
  EXPECT_LT(near_wall.distance_m, axis.distance_m - 0.2);
  ASSERT_TRUE(near_wall.interpolated);
  EXPECT_LT(near_wall.gradient.y(), -0.5);  // the distance grows towards the axis (−y here)
}

// Eviction by distance from the camera drops the planning cells beyond it with the TSDF: a
// space left far behind becomes unknown, not free with its obstacles forgotten.
TEST(PlanningScenes, EvictionMakesForgottenSpaceUnknown) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 1)));
  scene.add(sim::makePlane(Eigen::Vector3d(0, 1.5, 0), Eigen::Vector3d(0, -1, 0)));
  MapperConfig config = planningSceneConfig();
  config.max_depth_m = 4.0;
  config.max_distance_from_camera_m = 6.0;
  config.occupancy_min_weight = 1.0;  // the wall ahead is seen by one or two views at a time
  Mapper mapper(config);
  for (int i = 0; i < 16; ++i) {
    const Eigen::Vector3d eye(1.0 * i, 0.0, 1.0);
    StereoFrame frame =
        renderFrame(scene, vgaCamera(), sim::lookAt(eye, eye + Eigen::Vector3d(1.0, 0.6, -0.3)));
    frame.timestamp_s = 1.0 + i;
    ASSERT_TRUE(mapper.integrate(frame).accepted);
    mapper.updatePlanning();
    if (i == 2) {
      ASSERT_EQ(mapper.planning()->state({2.0, 1.5, 1.0}), CellState::kOccupied);
    }
  }
  const PlanningMap& planning = *mapper.planning();
  EXPECT_EQ(planning.state({2.0, 1.5, 1.0}), CellState::kUnknown);  // 13 m behind the camera
  EXPECT_EQ(planning.state({2.0, 0.8, 1.0}), CellState::kUnknown);
  EXPECT_EQ(planning.state({17.0, 1.5, 1.0}), CellState::kOccupied);
  // No cell within the bound of the last camera is lost.
  planning.forEachKnownCell([&](const CellIndex& c, CellState, double) {
    EXPECT_LE((planning.grid().centre(c) - Eigen::Vector3d(15.0, 0.0, 1.0)).norm(),
              6.0 + planning.grid().blockM());
  });
}

// Queries from another thread while frames are fused and the layer updates: every answer is
// one the layer could give (states known or unknown, distances within the max), and nothing
// races (the ThreadSanitizer build runs this test).
TEST(PlanningScenes, QueriesWhileFusingAreSafe) {
  sim::AnalyticScene scene;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0, 0, 1.5);
  scene.add(sim::makeRoom(T, Eigen::Vector3d(2.0, 2.0, 1.5)));
  MapperConfig config = planningSceneConfig();
  config.num_threads = 2;
  Mapper mapper(config);
  const PlanningMap* planning = mapper.planning();
  std::atomic<bool> done{false};
  std::atomic<uint64_t> answered{0}, bad{0};
  std::thread reader([&] {
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < 200; ++i) points.emplace_back(-1.9 + 0.019 * i, 0.1, 1.2);
    std::vector<EsdfSample> samples;
    while (!done.load()) {
      planning->sampleBatch(points, &samples);
      for (const EsdfSample& s : samples) {
        const bool ok = s.state == CellState::kUnknown
                            ? std::isnan(s.distance_m)
                            : std::abs(s.distance_m) <= planning->config().max_distance_m;
        bad += !ok;
      }
      answered += samples.size();
    }
  });
  const int frames = test::quickMode() ? 4 : 10;
  for (int i = 0; i < frames; ++i) {
    const double a = 2.0 * M_PI * i / frames;
    const Eigen::Vector3d eye(0.5 * std::cos(a), 0.5 * std::sin(a), 1.2);
    StereoFrame frame = renderFrame(
        scene, vgaCamera(), sim::lookAt(eye, eye + Eigen::Vector3d(std::cos(a), std::sin(a), 0)));
    frame.timestamp_s = 1.0 + i;
    ASSERT_TRUE(mapper.integrate(frame).accepted);
    mapper.updatePlanning();
  }
  done = true;
  reader.join();
  EXPECT_GT(answered.load(), 0u);
  EXPECT_EQ(bad.load(), 0u);
  EXPECT_EQ(planning->state({1.2, 0.1, 1.2}), CellState::kFree);     // in front of the first camera
  EXPECT_EQ(planning->state({0.0, 0.0, 1.2}), CellState::kUnknown);  // behind every camera
}

}  // namespace
}  // namespace stereo_fusion

namespace stereo_fusion {
namespace {

// A caller that never calls updatePlanning() (a tool that only wants the mesh) does not make the
// map log grow without bound: integrate() updates the layer once too many changes wait, and the
// layer then answers as if it had been updated all along.
TEST(PlanningScenes, ChangesDoNotPileUpWhenNobodyUpdatesTheLayer) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane(Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d(-1, 0, 0)));
  MapperConfig config;
  config.mesh_enabled = false;
  Mapper mapper(config);
  size_t catch_ups = 0;
  // A frame of the wall changes hundreds of blocks: within these frames more than the 65 536
  // changes allowed would wait.
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d eye(0.0, 0.02 * i, 1.0);
    StereoFrame frame = test::renderFrame(scene, test::vgaCamera(),
                                          sim::lookAt(eye, eye + Eigen::Vector3d::UnitX()));
    frame.timestamp_s = 1.0 + i;
    const IntegrationResult r = mapper.integrate(frame);
    ASSERT_TRUE(r.accepted);
    catch_ups += r.planning_catch_up;
  }
  EXPECT_GT(catch_ups, 0u);
  EXPECT_EQ(mapper.planning()->state({3.0, 0.5, 1.0}), CellState::kOccupied);
}

}  // namespace
}  // namespace stereo_fusion
