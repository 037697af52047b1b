// The planning layer's evidence rule (occupancy_min_weight) and its sub-cell distances on
// analytic scenes: a floater seen once is no obstacle, one seen a few times is until views see
// through it, a thin pole seen from three views stays, and distances near a plane are those of
// the plane, not of the cell centres.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "PlanningSceneSupport.h"
#include "TestSupport.h"
#include "stereo_fusion/Mapper.h"

namespace stereo_fusion {
namespace {

using test::renderFrame;
using test::vgaCamera;

using test::planningSceneConfig;

/// A wall at x = 3 m, and optionally a floater: a 6 cm cube centred at (1.8, 0, 1) — a patch the
/// matcher put in mid-air, 1.2 m in front of the wall.
sim::AnalyticScene wallScene(bool with_floater) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane(Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d(-1, 0, 0)));
  if (with_floater) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(1.8, 0.0, 1.0);
    scene.add(sim::makeBox(T, Eigen::Vector3d(0.03, 0.03, 0.03)));
  }
  return scene;
}

/// Frame i of a camera sliding along y at x = 0, looking at +x.
StereoFrame wallFrame(const sim::AnalyticScene& scene, int i) {
  const Eigen::Vector3d eye(0.0, -0.15 + 0.05 * (i % 7), 1.0);
  StereoFrame frame =
      renderFrame(scene, vgaCamera(), sim::lookAt(eye, eye + Eigen::Vector3d::UnitX()));
  frame.timestamp_s = 1.0 + i;
  return frame;
}

const Eigen::Vector3d kFloater(1.78, 0.0, 1.0);  // inside the floater's front half

// One view of a floater holds weight ~1 < occupancy_min_weight (2): no obstacle. With the
// minimum at the smallest weight (every observed voxel is evidence, the rule before it) the
// same view makes the cell occupied: the test would fail without the rule.
TEST(PlanningEvidence, AFloaterSeenOnceIsNoObstacle) {
  const sim::AnalyticScene with = wallScene(true);
  for (const double min_weight : {2.0, 1e-3}) {
    MapperConfig config = planningSceneConfig();
    config.occupancy_min_weight = min_weight;
    Mapper mapper(config);
    ASSERT_TRUE(mapper.integrate(wallFrame(with, 0)).accepted);
    mapper.updatePlanning();
    const CellState state = mapper.planning()->state(kFloater);
    if (min_weight > 1.0) {
      EXPECT_NE(state, CellState::kOccupied);
      EXPECT_NE(mapper.planning()->state({3.02, 0.3, 1.0}), CellState::kOccupied)
          << "a wall seen once is no evidence either";
    } else {
      EXPECT_EQ(state, CellState::kOccupied);
    }
  }
}

// A floater seen by 4 views is an obstacle (they agree); later views that see through it to
// the wall make its cell free again (carving's decay and −Φ), and the wall stays occupied.
TEST(PlanningEvidence, AFloaterSeenThroughBecomesFree) {
  const sim::AnalyticScene with = wallScene(true), without = wallScene(false);
  Mapper mapper(planningSceneConfig());
  int i = 0;
  for (; i < 4; ++i) ASSERT_TRUE(mapper.integrate(wallFrame(with, i)).accepted);
  mapper.updatePlanning();
  ASSERT_EQ(mapper.planning()->state(kFloater), CellState::kOccupied);
  int seen_through = 0;
  for (; i < 40 && mapper.planning()->state(kFloater) == CellState::kOccupied; ++i) {
    ASSERT_TRUE(mapper.integrate(wallFrame(without, i)).accepted);
    mapper.updatePlanning();
    ++seen_through;
  }
  EXPECT_EQ(mapper.planning()->state(kFloater), CellState::kFree);
  EXPECT_LE(seen_through, 12) << "views seeing through it before it is free";
  EXPECT_EQ(mapper.planning()->state({3.02, 0.0, 1.0}), CellState::kOccupied);
}

// A pole 4 cm across (2 cm radius), 2 m from the cameras, seen from three views 0.3 m apart
// (half a metre of parallax at the pole): it stays an obstacle over its whole height in view.
TEST(PlanningEvidence, AThinPoleSeenFromThreeViewsStaysOccupied) {
  sim::AnalyticScene scene;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(2.0, 0.0, 1.0);
  scene.add(sim::makeCylinder(T, 0.02, 0.6));
  scene.add(sim::makePlane(Eigen::Vector3d(4.0, 0, 0), Eigen::Vector3d(-1, 0, 0)));
  Mapper mapper(planningSceneConfig());
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d eye(0.0, -0.3 + 0.3 * i, 1.0);
    StereoFrame frame =
        renderFrame(scene, vgaCamera(), sim::lookAt(eye, Eigen::Vector3d(2.0, 0.0, 1.0)));
    frame.timestamp_s = 1.0 + i;
    ASSERT_TRUE(mapper.integrate(frame).accepted);
  }
  mapper.updatePlanning();
  const PlanningMap& planning = *mapper.planning();
  for (double z = 0.6; z <= 1.4001; z += 0.08) {
    // The pole's cells: any cell within 2 cm of its axis at this height.
    bool occupied = false;
    for (double dx : {-0.02, 0.0, 0.02})
      for (double dy : {-0.02, 0.0, 0.02})
        occupied |= planning.state({2.0 + dx, dy, z}) == CellState::kOccupied;
    EXPECT_TRUE(occupied) << "z " << z;
  }
  // And it is an obstacle to the distance field: 0.5 m beside it reads about 0.5 m.
  const EsdfSample beside = planning.sample({2.0, 0.5, 1.0});
  ASSERT_EQ(beside.state, CellState::kFree);
  EXPECT_NEAR(beside.distance_m, 0.48, 0.06);
}

// A floor at z = 0 seen from 1 m up: every free cell's distance is its centre's height (the
// analytic distance to the plane), to a centimetre at the median — not the distance to the
// occupied cell's centre 4 cm below the surface, which put every cell 4 cm too far (half a
// cell) before the sub-cell rule.
TEST(PlanningEvidence, DistancesAboveAPlaneAreSubCell) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 1)));
  Mapper mapper(planningSceneConfig());
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector3d eye(0.1 * i, 0.05 * i, 1.0);
    StereoFrame frame =
        renderFrame(scene, vgaCamera(), sim::lookAt(eye, eye + Eigen::Vector3d(1.0, 0.2, -0.8)));
    frame.timestamp_s = 1.0 + i;
    ASSERT_TRUE(mapper.integrate(frame).accepted);
  }
  mapper.updatePlanning();
  const PlanningMap& planning = *mapper.planning();
  std::vector<double> errors;
  planning.forEachKnownCell([&](const CellIndex& c, CellState state, double distance_m) {
    const Eigen::Vector3d centre = planning.grid().centre(c);
    if (state != CellState::kFree || centre.z() > 0.5 || std::abs(centre.y()) > 0.6 ||
        centre.x() < 1.0 || centre.x() > 2.0)
      return;
    errors.push_back(std::abs(distance_m - centre.z()));
  });
  ASSERT_GT(errors.size(), 50u);
  std::sort(errors.begin(), errors.end());
  const double median = errors[errors.size() / 2], p90 = errors[errors.size() * 9 / 10];
  EXPECT_LT(median, 0.01);  // measured 0.85 cm; every cell read +4 cm before
  EXPECT_LT(p90, 0.025);    // measured 1.8 cm
}

}  // namespace
}  // namespace stereo_fusion
