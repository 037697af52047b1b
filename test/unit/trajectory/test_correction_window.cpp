// CorrectionWindow and refuseWindow(): a loop closure's correction re-fuses the kept frames at
// their corrected poses; the result is exactly the map of those frames fused there, and frames
// that left the window stay where the base put them.
#include <gtest/gtest.h>

#include "MeshTestSupport.h"
#include <tuple>

#include "stereo_fusion/trajectory/CorrectionWindow.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

constexpr int kFrames = 8;

/// Odometry's view of pose `T_true` at frame i: 0.5° of yaw about the first camera and 1 cm per frame.
Eigen::Isometry3d drifted(int i, const Eigen::Isometry3d& T_true) {
  const Eigen::Vector3d pivot = floorAndSphereView(0).translation();
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  D.linear() = Eigen::AngleAxisd(0.5 * i * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  D.translation() = pivot - D.linear() * pivot + Eigen::Vector3d(0.01 * i, 0.0, 0.0);
  return D * T_true;
}

/// Frame i of floorAndSphere() rendered from the true pose, carrying the drifted one.
StereoFrame driftingFrame(int i) {
  StereoFrame f = renderFrame(floorAndSphere(), qvgaCamera(), floorAndSphereView(i), 0.2, i);
  f.timestamp_s = 1.0 + i;
  f.T_world_camera = drifted(i, floorAndSphereView(i));
  return f;
}

MapperConfig windowConfig() {
  MapperConfig config;
  config.histogram_min_points = 0;
  return config;
}

/// The SLAM's corrected trajectory: the true poses of frames 0, 3, 6 and 7.
std::vector<StampedPose> keyframes() {
  std::vector<StampedPose> poses;
  for (int i : {0, 3, 6, 7}) poses.push_back({1.0 + i, floorAndSphereView(i)});
  return poses;
}

}  // namespace

TEST(CorrectionWindow, RefusingTheWindowEqualsFusingTheFramesAtTheirCorrectedPoses) {
  const MapperConfig config = windowConfig();
  Mapper live(config);
  CorrectionWindow window(config, 100);
  std::vector<StereoFrame> frames;
  for (int i = 0; i < kFrames; ++i) {
    frames.push_back(driftingFrame(i));
    ASSERT_TRUE(live.integrate(frames.back()).accepted);
    window.add(frames.back());
  }
  EXPECT_EQ(window.size(), static_cast<size_t>(kFrames));
  EXPECT_EQ(window.framesFrozen(), 0u);
  EXPECT_EQ(window.bytes(), kFrames * (320u * 240u * 4u + 320u * 240u * 3u));
  EXPECT_TRUE(window.baseBytes().empty());

  const PoseCorrection correction(window.originalPoses(), keyframes(), frames.back().timestamp_s);
  ASSERT_EQ(correction.corrections().size(), 4u);
  // The keyframes land on their true poses.
  for (int i : {0, 3, 6, 7})
    EXPECT_TRUE(correction.corrected(frames[i].timestamp_s, frames[i].T_world_camera).isApprox(floorAndSphereView(i), 1e-9));
  double shift_m = 0, rotation_deg = 0;
  const std::vector<StereoFrame> kept(window.frames().begin(), window.frames().end());
  correctionMagnitude(window.originalPoses(), correction, &shift_m, &rotation_deg);
  EXPECT_NEAR(rotation_deg, 3.5, 1e-6);  // frame 7: 0.5° per frame
  EXPECT_GT(shift_m, 0.07);

  size_t rejected = 99;
  std::string error;
  const std::unique_ptr<Mapper> refused = refuseWindow(config, window.baseBytes(), kept, correction, {}, &rejected, &error);
  ASSERT_TRUE(refused) << error;
  EXPECT_EQ(rejected, 0u);

  Mapper reference(config);
  for (StereoFrame f : frames) {
    f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f).accepted);
  }
  EXPECT_TRUE(snapshot(refused->map()) == snapshot(reference.map()));
  EXPECT_FALSE(snapshot(refused->map()) == snapshot(live.map())) << "the correction must move the map";
  EXPECT_TRUE(triangleSets(refused->mesh()) == triangleSets(reference.mesh()));
  expectMeshEqualsRebuild(*refused);
  // The planning layer swapped in with it is the reference's too: the same cells, states and
  // distances, though the reference updated it after every frame and the refusal once.
  reference.updatePlanning();
  live.updatePlanning();
  auto cells = [](const Mapper& m) {
    std::vector<std::tuple<int, int, int, int, double>> out;
    m.planning()->forEachKnownCell([&](const CellIndex& c, CellState s, double d) {
      out.emplace_back(c.x, c.y, c.z, static_cast<int>(s), d);
    });
    return out;
  };
  const auto refused_cells = cells(*refused);
  EXPECT_FALSE(refused_cells.empty());
  EXPECT_TRUE(refused_cells == cells(reference));
  EXPECT_FALSE(refused_cells == cells(live)) << "the correction must move the planning layer";
}

TEST(CorrectionWindow, FramesThatLeftTheWindowStayWhereTheBaseFusedThem) {
  const MapperConfig config = windowConfig();
  CorrectionWindow window(config, 3);
  std::vector<StereoFrame> frames;
  for (int i = 0; i < kFrames; ++i) {
    frames.push_back(driftingFrame(i));
    window.add(frames.back());
  }
  ASSERT_EQ(window.size(), 3u);
  EXPECT_EQ(window.framesFrozen(), static_cast<uint64_t>(kFrames - 3));
  EXPECT_FALSE(window.baseBytes().empty());
  const PoseCorrection correction(window.originalPoses(), keyframes(), frames.back().timestamp_s);
  // Only the keyframes 6 and 7 lie within the window's frames (5, 6, 7).
  EXPECT_EQ(correction.corrections().size(), 2u);
  const std::vector<StereoFrame> kept(window.frames().begin(), window.frames().end());
  std::string error;
  const std::unique_ptr<Mapper> refused = refuseWindow(config, window.baseBytes(), kept, correction, {}, nullptr, &error);
  ASSERT_TRUE(refused) << error;

  // The first five frames at their original poses (no correction was known when they left),
  // the last three at their corrected ones.
  Mapper reference(config);
  for (int i = 0; i < kFrames; ++i) {
    StereoFrame f = frames[i];
    if (i >= kFrames - 3) f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f).accepted);
  }
  EXPECT_TRUE(snapshot(refused->map()) == snapshot(reference.map()));
}

TEST(CorrectionWindow, ACorrectionKnownWhenAFrameLeavesIsAppliedToIt) {
  const MapperConfig config = windowConfig();
  CorrectionWindow window(config, 2);
  std::vector<StereoFrame> frames;
  for (int i = 0; i < 3; ++i) frames.push_back(driftingFrame(i));
  window.add(frames[0]);
  window.add(frames[1]);
  const PoseCorrection correction(window.originalPoses(), {{1.0, floorAndSphereView(0)}, {2.0, floorAndSphereView(1)}}, 2.0);
  window.setCorrection(correction);
  window.add(frames[2]);  // frame 0 leaves, at its corrected (true) pose
  Mapper reference(config);
  StereoFrame first = frames[0];
  first.T_world_camera = correction.corrected(first.timestamp_s, first.T_world_camera);
  ASSERT_TRUE(reference.integrate(first).accepted);
  BlockOctree base(config.blockSizeM());
  MapFileInfo info;
  std::string error;
  const std::vector<uint8_t> bytes = window.baseBytes();
  ASSERT_TRUE(decodeMapFile(bytes.data(), bytes.size(), config, &base, &info, &error)) << error;
  EXPECT_TRUE(snapshot(base) == snapshot(reference.map()));
}

TEST(CorrectionWindow, NothingIsKeptWithZeroFramesAndACancelledRefusalReturnsNothing) {
  const MapperConfig config = windowConfig();
  CorrectionWindow none(config, 0);
  none.add(driftingFrame(0));
  EXPECT_EQ(none.size(), 0u);
  EXPECT_EQ(none.bytes(), 0u);
  std::string error;
  const std::unique_ptr<Mapper> cancelled =
      refuseWindow(config, {}, {driftingFrame(0)}, PoseCorrection(), [] { return true; }, nullptr, &error);
  EXPECT_FALSE(cancelled);
  EXPECT_EQ(error, "cancelled");
}

TEST(CorrectionWindow, AClearIsRepeatedAfterTheFramesStampedBeforeIt) {
  const MapperConfig config = windowConfig();
  CorrectionWindow window(config, 100);
  std::vector<StereoFrame> frames;
  const MapRegion ball = MapRegion::sphere({0.05, 0.1, 1.2}, 0.3);
  for (int i = 0; i < kFrames; ++i) {
    frames.push_back(driftingFrame(i));  // stamped 1 + i
    window.add(frames.back());
    if (i == 3) window.clearRegion(ball, 4.5);
  }
  ASSERT_EQ(window.clears().size(), 1u);
  const PoseCorrection correction(window.originalPoses(), keyframes(), frames.back().timestamp_s);
  const std::vector<StereoFrame> kept(window.frames().begin(), window.frames().end());
  std::string error;
  const std::unique_ptr<Mapper> refused =
      refuseWindow(config, window.baseBytes(), kept, correction, {}, nullptr, &error, window.clears());
  ASSERT_TRUE(refused) << error;
  Mapper reference(config);
  for (int i = 0; i < kFrames; ++i) {
    if (i == 4) {
      ASSERT_TRUE(reference.clearRegion(ball).accepted);
    }
    StereoFrame f = frames[i];
    f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f).accepted);
  }
  EXPECT_TRUE(snapshot(refused->map()) == snapshot(reference.map()));
  // Without the clear the maps differ: the test would see a refusal that forgot it.
  const std::unique_ptr<Mapper> forgetful = refuseWindow(config, window.baseBytes(), kept, correction, {}, nullptr, &error);
  EXPECT_FALSE(snapshot(forgetful->map()) == snapshot(reference.map()));
  // Once every frame older than the clear has left the window, the clear is dropped.
  for (int i = 0; i < 100; ++i) {
    StereoFrame f = driftingFrame(i % kFrames);
    f.timestamp_s = 100.0 + i;
    window.add(f);
  }
  EXPECT_TRUE(window.clears().empty());
}

TEST(CorrectionWindow, ALoadedMapBecomesTheBaseTheNewFramesAreRefusedOver) {
  const MapperConfig config = windowConfig();
  // A map from an earlier session (frames 0–2 at their true poses), loaded; then frames 3–7.
  Mapper earlier(config);
  for (int i = 0; i < 3; ++i) {
    StereoFrame f = renderFrame(floorAndSphere(), qvgaCamera(), floorAndSphereView(i), 0.2, i);
    f.timestamp_s = 0.1 * (i + 1);
    ASSERT_TRUE(earlier.integrate(f).accepted);
  }
  std::vector<uint8_t> bytes = earlier.encodeMap();
  sealMapFile(&bytes);
  CorrectionWindow window(config, 100);
  std::string error;
  ASSERT_TRUE(window.clear(bytes, &error)) << error;
  EXPECT_EQ(window.size(), 0u);
  std::vector<StereoFrame> frames;
  for (int i = 3; i < kFrames; ++i) {
    frames.push_back(driftingFrame(i));
    window.add(frames.back());
  }
  const PoseCorrection correction(window.originalPoses(), keyframes(), frames.back().timestamp_s);
  const std::vector<StereoFrame> kept(window.frames().begin(), window.frames().end());
  const std::unique_ptr<Mapper> refused = refuseWindow(config, window.baseBytes(), kept, correction, {}, nullptr, &error);
  ASSERT_TRUE(refused) << error;
  // The loaded map, then the new frames at their corrected poses.
  Mapper reference(config);
  BlockOctree loaded(config.blockSizeM());
  MapFileInfo info;
  ASSERT_TRUE(decodeMapFile(bytes.data(), bytes.size(), config, &loaded, &info, &error)) << error;
  reference.adoptMap(&loaded, info);
  for (StereoFrame f : frames) {
    f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f).accepted);
  }
  EXPECT_TRUE(snapshot(refused->map()) == snapshot(reference.map()));
  // Without the base the re-fusion would lose the loaded map.
  const std::unique_ptr<Mapper> baseless = refuseWindow(config, {}, kept, correction, {}, nullptr, &error);
  EXPECT_LT(baseless->map().blockCount(), refused->map().blockCount());
  // A broken base is reported, and the window starts empty.
  bytes.resize(bytes.size() / 2);
  EXPECT_FALSE(window.clear(bytes, &error));
  EXPECT_TRUE(window.baseBytes().empty());
}
