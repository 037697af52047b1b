// The offline fuser's --trajectory: after the last frame the frames are fused again at the
// poses a SLAM's corrected trajectory implies (a loop closure applied offline).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "MeshTestSupport.h"
#include "fuser/FuseArguments.h"
#include "fuser/OfflineFuser.h"
#include "readers/DatasetReader.h"
#include "readers/PlyReader.h"
#include "simulator/DatasetWriter.h"
#include "stereo_fusion/io/PlyWriter.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;
namespace fs = std::filesystem;

namespace {

constexpr int kFrames = 6;

/// Odometry's pose of frame i: 0.5° of yaw about the first camera and 1.5 cm along x per frame.
Eigen::Isometry3d drifted(int i) {
  const Eigen::Vector3d pivot = floorAndSphereView(0).translation();
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  D.linear() =
      Eigen::AngleAxisd(0.5 * i * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  D.translation() = pivot - D.linear() * pivot + Eigen::Vector3d(0.015 * i, 0.0, 0.0);
  return D * floorAndSphereView(i);
}

double stamp(int i) { return 0.1 * (i + 1); }

void writeTum(const std::string& path, const std::vector<int>& frames,
              double stamp_offset_s = 0.0) {
  std::ofstream out(path);
  for (int i : frames) {
    const Eigen::Isometry3d T = floorAndSphereView(i);
    const Eigen::Quaterniond q(T.rotation());
    char line[256];
    std::snprintf(line, sizeof(line), "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n",
                  stamp(i) + stamp_offset_s, T.translation().x(), T.translation().y(),
                  T.translation().z(), q.x(), q.y(), q.z(), q.w());
    out << line;
  }
}

/// Mean distance of the mesh's vertices to the true scene.
double meanError(const std::string& ply) {
  TriangleMesh mesh;
  std::string error;
  EXPECT_TRUE(readPly(ply, &mesh, &error)) << error;
  const sim::AnalyticScene scene = floorAndSphere();
  double sum = 0.0;
  for (const Eigen::Vector3f& p : mesh.positions) sum += scene.distanceToSurface(p.cast<double>());
  return mesh.positions.empty() ? 1e9 : sum / mesh.positions.size();
}

class FuserTrajectory : public testing::Test {
 protected:
  void SetUp() override {
    seq_ = fs::path(testing::TempDir()) /
           ("stereo_fusion_trajectory_seq_" + std::to_string(::getpid()));
    fs::remove_all(seq_);
    std::string error;
    auto writer = sim::DatasetWriter::create(seq_.string(), qvgaCamera(), &error);
    ASSERT_TRUE(writer) << error;
    const sim::AnalyticScene scene = floorAndSphere();
    for (int i = 0; i < kFrames; ++i) {
      const StereoFrame f = renderFrame(scene, qvgaCamera(), floorAndSphereView(i));
      ASSERT_TRUE(
          writer->writeFrame(i, stamp(i), drifted(i), f.disparity_px, f.color, cv::Mat(), &error))
          << error;
    }
  }
  void TearDown() override { fs::remove_all(seq_); }
  fs::path seq_;
};

}  // namespace

TEST_F(FuserTrajectory, TheFramesAreFusedAgainAtTheCorrectedPosesAndLandOnTheTruth) {
  const std::string trajectory = (seq_ / "trajectory.txt").string();
  writeTum(trajectory, {0, 2, 4, 5});
  std::string error;
  FuseOptions drifting, corrected;
  ASSERT_TRUE(
      parseFuseArguments({seq_.string(), (seq_ / "drift").string(), "--quiet"}, &drifting, &error))
      << error;
  ASSERT_TRUE(parseFuseArguments(
      {seq_.string(), (seq_ / "corr").string(), "--quiet", "--trajectory", trajectory}, &corrected,
      &error))
      << error;
  FuseReport drift_report, report;
  ASSERT_TRUE(runOfflineFusion(drifting, &drift_report, &error)) << error;
  ASSERT_TRUE(runOfflineFusion(corrected, &report, &error)) << error;
  EXPECT_FALSE(drift_report.correction.applied);
  ASSERT_TRUE(report.correction.applied);
  EXPECT_EQ(report.correction.trajectory_poses, 4u);
  EXPECT_EQ(report.correction.matched_poses, 4u);
  EXPECT_EQ(report.correction.frames_refused, static_cast<size_t>(kFrames));
  EXPECT_EQ(report.correction.frames_rejected, 0u);
  EXPECT_NEAR(report.correction.max_rotation_deg, 2.5, 1e-6);  // frame 5
  std::ifstream stats_file((seq_ / "corr" / "stats.json").string());
  const std::string stats((std::istreambuf_iterator<char>(stats_file)),
                          std::istreambuf_iterator<char>());
  EXPECT_NE(stats.find("\"frames_refused\": 6"), std::string::npos);

  // Exactly the map of the frames fused at PoseCorrection's poses.
  auto reader = DatasetReader::open(seq_.string(), &error);
  ASSERT_TRUE(reader) << error;
  std::vector<DatasetFrameInfo> lines;
  ASSERT_TRUE(readTumPoses(trajectory, &lines, &error)) << error;
  std::vector<StampedPose> keyframes, originals;
  for (const DatasetFrameInfo& l : lines) keyframes.push_back({l.timestamp_s, l.T_world_camera});
  for (size_t i = 0; i < reader->size(); ++i)
    originals.push_back({reader->info(i).timestamp_s, reader->info(i).T_world_camera});
  const PoseCorrection correction(originals, keyframes, 1e9);
  Mapper reference(corrected.config);
  for (size_t i = 0; i < reader->size(); ++i) {
    StereoFrame f;
    ASSERT_TRUE(reader->load(i, &f, &error)) << error;
    f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f, MeshTiming::kDeferred).accepted);
  }
  reference.updateMesh();
  const std::string reference_ply = (seq_ / "reference.ply").string();
  ASSERT_TRUE(writePly(reference_ply, reference.extractMesh(), &error)) << error;
  EXPECT_TRUE(readBytes(reference_ply) == readBytes((seq_ / "corr" / "mesh.ply").string()));

  // The corrected mesh lies on the truth; the drifted one does not.
  const double drift_error = meanError((seq_ / "drift" / "mesh.ply").string());
  const double corrected_error = meanError((seq_ / "corr" / "mesh.ply").string());
  std::printf("[trajectory] mean vertex error: drifting %.4f m, corrected %.4f m\n", drift_error,
              corrected_error);
  EXPECT_LT(corrected_error, 0.5 * drift_error);
  EXPECT_LT(corrected_error, 0.01);
}

TEST_F(FuserTrajectory, ATrajectoryThatMatchesNoFrameOrIsMalformedIsOneClearError) {
  std::string error;
  const std::string far = (seq_ / "far.txt").string();
  writeTum(far, {0, 5}, 100.0);
  FuseOptions options;
  ASSERT_TRUE(parseFuseArguments(
      {seq_.string(), (seq_ / "out").string(), "--quiet", "--trajectory", far}, &options, &error));
  FuseReport report;
  EXPECT_FALSE(runOfflineFusion(options, &report, &error));
  EXPECT_NE(error.find("none of its 2 stamps lies within 0.5 s of a fused frame"),
            std::string::npos)
      << error;

  const std::string bad = (seq_ / "bad.txt").string();
  std::ofstream(bad) << "0.1 1 2 3\n";
  ASSERT_TRUE(parseFuseArguments(
      {seq_.string(), (seq_ / "out").string(), "--quiet", "--trajectory", bad}, &options, &error));
  EXPECT_FALSE(runOfflineFusion(options, &report, &error));
  EXPECT_NE(error.find("bad.txt:1: expected 8 numbers"), std::string::npos) << error;

  FuseOptions no_input;
  EXPECT_FALSE(parseFuseArguments(
      {(seq_ / "out").string(), "--load-map", "x.sfmap", "--trajectory", bad}, &no_input, &error));
  EXPECT_NE(error.find("--trajectory needs the frames it corrects"), std::string::npos) << error;
}
