#pragma once
// Shared by the session's tests: a drifting floor-and-sphere sequence and a re-fusion of a
// timeline's snapshot.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "MeshTestSupport.h"
#include "stereo_fusion/session/EditTimeline.h"

namespace stereo_fusion::test {

constexpr int kFrames = 8;

/// Odometry's view of pose `T_true` at frame i: 0.5° of yaw about the first camera and 1 cm per
/// frame.
inline Eigen::Isometry3d drifted(int i, const Eigen::Isometry3d& T_true) {
  const Eigen::Vector3d pivot = floorAndSphereView(0).translation();
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  D.linear() =
      Eigen::AngleAxisd(0.5 * i * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  D.translation() = pivot - D.linear() * pivot + Eigen::Vector3d(0.01 * i, 0.0, 0.0);
  return D * T_true;
}

/// Frame i of floorAndSphere() rendered from the true pose, carrying the drifted one, stamped 1 +
/// i.
inline StereoFrame driftingFrame(int i) {
  StereoFrame f = renderFrame(floorAndSphere(), qvgaCamera(), floorAndSphereView(i), 0.2, i);
  f.timestamp_s = 1.0 + i;
  f.T_world_camera = drifted(i, floorAndSphereView(i));
  return f;
}

inline MapperConfig sessionTestConfig() {
  MapperConfig config;
  config.histogram_min_points = 0;
  return config;
}

/// The SLAM's corrected trajectory: the true poses of frames 0, 3, 6 and 7.
inline std::vector<StampedPose> keyframes() {
  std::vector<StampedPose> poses;
  for (int i : {0, 3, 6, 7}) poses.push_back({1.0 + i, floorAndSphereView(i)});
  return poses;
}

inline Edit frameEdit(const StereoFrame& frame, uint64_t ticket) {
  Edit e;
  e.kind = Edit::Kind::kFrame;
  e.ticket = ticket;
  e.stamp_s = frame.timestamp_s;
  e.frame = frame;
  return e;
}

inline Edit clearEdit(const MapRegion& region, uint64_t ticket, double stamp_s) {
  Edit e;
  e.kind = Edit::Kind::kClear;
  e.ticket = ticket;
  e.stamp_s = stamp_s;
  e.region = region;
  return e;
}

/// The map a correction re-fuses from `timeline`'s snapshot, meshed.
inline std::unique_ptr<Mapper> refuseSnapshot(const MapperConfig& config,
                                              const EditTimeline& timeline,
                                              const PoseCorrection& correction,
                                              RefusionProgress* progress = nullptr) {
  EditTimeline::Snapshot snapshot = timeline.snapshot();
  std::string error;
  std::unique_ptr<Mapper> mapper = mapperFromBase(config, snapshot.base_bytes, &error);
  EXPECT_TRUE(mapper) << error;
  if (!mapper) return mapper;
  EditReplay replay(snapshot.base_pending);
  RefusionProgress local;
  EXPECT_EQ(replayEdits(snapshot.edits, correction, mapper.get(), &replay, {},
                        progress ? progress : &local, &error),
            RefusionStatus::kDone)
      << error;
  mapper->updateMesh();
  return mapper;
}

}  // namespace stereo_fusion::test
