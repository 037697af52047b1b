// ContradictionFilter against a wall fused from four exact views (3 m ahead, f·b = 52.5 px·m:
// d = 17.5 px, σ_z = 3²·0.15/52.5 = 2.6 cm): measurements far behind it are dropped when
// isolated and kept when a region agrees; nearer ones and small disagreements are kept.
#include <gtest/gtest.h>

#include <cmath>

#include <opencv2/core.hpp>

#include "TestSupport.h"
#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/integration/ContradictionFilter.h"

namespace stereo_fusion {
namespace {

using test::renderFrame;
using test::vgaCamera;

sim::AnalyticScene wall() {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane(Eigen::Vector3d(0, 0, 3.0), Eigen::Vector3d(0, 0, -1)));
  return scene;
}

Eigen::Isometry3d pose(double x_m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().x() = x_m;
  return T;
}

MapperConfig config(int threads = 2) {
  MapperConfig c;
  c.voxel_size_m = 0.02;
  c.num_threads = threads;
  c.mesh_enabled = false;
  c.planning_enabled = false;
  c.contradiction_filter = false;  // the map is built without it; the test applies it
  return c;
}

/// The wall and a 12 cm floater 0.5 m in front of it (25 px wide: the wall behind it is never
/// seen, so only the floater's surface projects into the tiles at its middle).
sim::AnalyticScene wallAndFloater() {
  sim::AnalyticScene scene = wall();
  Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
  at.translation() = Eigen::Vector3d(0.0, 0.0, 2.56);
  scene.add(sim::makeBox(at, Eigen::Vector3d(0.06, 0.06, 0.06)));
  return scene;
}

/// The wall (with the floater if `floater`) seen four times: weight 4 on its surface voxels.
const Mapper& wallMap(int threads, bool floater = false) {
  static Mapper* maps[3][2] = {};
  Mapper*& mapper = maps[threads][floater];
  if (!mapper) {
    mapper = new Mapper(config(threads));
    const sim::AnalyticScene scene = floater ? wallAndFloater() : wall();
    for (int i = 0; i < 4; ++i)
      EXPECT_TRUE(mapper->integrate(renderFrame(scene, vgaCamera(), pose(0.01 * i))).accepted);
  }
  return *mapper;
}

struct Filtered {
  ContradictionStats stats;
  int unusable = 0;  // pixels without a depth after the filter
};

/// The wall's frame from the origin with disparities in `rect` changed by `delta_px`.
Filtered filterFrame(const cv::Rect& rect, float delta_px, int threads = 2,
                     bool map_with_floater = false) {
  const Mapper& mapper = wallMap(threads, map_with_floater);
  StereoFrame frame = renderFrame(wall(), vgaCamera(), pose(0.0));
  cv::Mat patch = frame.disparity_px(rect);
  patch += cv::Scalar(delta_px);
  const MapperConfig c = config(threads);
  ThreadPool pool(threads);
  MeasurementImage measurements;
  measurements.build(frame, stageConfigs(c).pipeline.measurement, &pool);
  ContradictionFilter filter;
  Filtered out;
  out.stats = filter.apply(frame, mapper.tsdf(), mapper.tsdf().blocksSortedByKey(),
                           stageConfigs(c).pipeline.contradiction, c.disparity_noise_px, &pool,
                           &measurements);
  for (int i = 0; i < measurements.width() * measurements.height(); ++i)
    out.unusable += std::isnan(measurements.depths()[i]);
  return out;
}

// An 8×8 patch 1.5 px too small (z = 52.5/16 = 3.28 m): beyond the wall's surface plus a voxel
// (≤ 3.08 m) plus 2σ_z (6.2 cm at 3.28 m), and isolated: its 64 pixels are dropped, nothing else.
TEST(ContradictionFilter, AnIsolatedPatchBehindAConfidentWallIsDropped) {
  const Filtered f = filterFrame(cv::Rect(320, 240, 8, 8), -1.5f);
  EXPECT_GT(f.stats.tiles_with_surface, 3000u);
  EXPECT_EQ(f.stats.pixels_behind, 64u);
  EXPECT_EQ(f.stats.pixels_rejected, 64u);
  EXPECT_EQ(f.unusable, 64);
}

// 0.2 px too small (z = 3.035 m) is within the wall's surface plus a voxel and 2σ_z: kept. So is
// a patch 1.5 px too large, in front of the wall (the rule drops only what lies behind).
TEST(ContradictionFilter, SmallDisagreementsAndMeasurementsInFrontAreKept) {
  EXPECT_EQ(filterFrame(cv::Rect(320, 240, 8, 8), -0.2f).stats.pixels_rejected, 0u);
  const Filtered front = filterFrame(cv::Rect(320, 240, 8, 8), 1.5f);
  EXPECT_EQ(front.stats.pixels_behind, 0u);
  EXPECT_EQ(front.unusable, 0);
}

// A 200×200-px region behind the wall (the wall moved back, an object left): every window of
// 5×5 tiles over it holds more than a quarter of pixels behind, so none is dropped.
TEST(ContradictionFilter, ARegionBehindIsAChangeAndKept) {
  const Filtered f = filterFrame(cv::Rect(200, 140, 200, 200), -1.5f);
  EXPECT_EQ(f.stats.pixels_behind, 200u * 200u);
  EXPECT_EQ(f.stats.pixels_rejected, 0u);
  EXPECT_EQ(f.unusable, 0);
}

// The map holds a confident floater the frame does not see (it measures the wall there): the
// floater's tile is not trusted — the tiles around measure the wall, far behind it — so the
// wall's pixels behind it are kept.
TEST(ContradictionFilter, AFloaterTheFrameSeesThroughDropsNothing) {
  const Filtered f = filterFrame(cv::Rect(0, 0, 1, 1), 0.0f, 2, /*map_with_floater=*/true);
  EXPECT_GT(f.stats.pixels_behind, 40u);   // behind the floater's surface ...
  EXPECT_EQ(f.stats.pixels_rejected, 0u);  // ... which is not trusted
  EXPECT_EQ(f.unusable, 0);
}

TEST(ContradictionFilter, DoesNotDependOnTheThreadCount) {
  const Filtered one = filterFrame(cv::Rect(100, 96, 16, 8), -2.0f, 1);
  const Filtered two = filterFrame(cv::Rect(100, 96, 16, 8), -2.0f, 2);
  EXPECT_EQ(one.stats.tiles_with_surface, two.stats.tiles_with_surface);
  EXPECT_EQ(one.stats.pixels_rejected, two.stats.pixels_rejected);
  EXPECT_EQ(one.stats.pixels_rejected, 128u);
}

}  // namespace
}  // namespace stereo_fusion
