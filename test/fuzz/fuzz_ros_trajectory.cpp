// Fuzz target: a SLAM's corrected trajectory as ROS delivers it — a nav_msgs/Path with fuzzed
// stamps, positions and quaternions — through toCameraPoses() (the node's conversion) into
// MappingSession::submitTrajectory() over three kept frames, and a re-fusion when it is taken.
// Input layout (ByteReader: a short input reads as zeros):
//   byte 0  flags  bit 0 raw float quaternions (else a rotation scaled from bytes, its norm off 1
//                        by up to ±2 %)
//                  bit 1 raw float positions (else within ±1 m)
//                  bit 2 stamps from bytes anywhere in [0, 8] s (else near the kept frames')
//                  bit 3 a clear between the frames and the trajectory
//   byte 1  poses (mod 6), then per pose: stamp, position, quaternion
// Every Path is refused with a reason or has an outcome; a trajectory the session refuses or
// fails leaves the map as it was; the mesh stays finite with valid indices.
#include <Eigen/Geometry>
#include <cmath>
#include <memory>

#include "FuzzSupport.h"
#include "stereo_fusion/ros/MessageConversions.h"
#include "stereo_fusion/session/MappingSession.h"

using namespace stereo_fusion;

namespace {

constexpr int kFrames = 3;

/// A wall 2 m ahead (disparity 1.5 px at f = 30 px, b = 0.1 m), seen from x = 0, 0.05, 0.1 m at
/// stamps 1, 2, 3 s.
StereoFrame frame(int i) {
  StereoFrame f;
  f.camera = *StereoCamera::create(32, 24, 30.0, 30.0, 15.5, 11.5, 0.1);
  f.disparity_px = cv::Mat(24, 32, CV_32FC1, cv::Scalar(1.5f));
  f.timestamp_s = 1.0 + i;
  f.T_world_camera = Eigen::Isometry3d::Identity();
  f.T_world_camera.translation().x() = 0.05 * i;
  return f;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::ByteReader in(data, size);
  const uint8_t flags = in.u8();
  const int pose_count = in.u8() % 6;

  nav_msgs::Path path;
  for (int k = 0; k < pose_count; ++k) {
    geometry_msgs::PoseStamped p;
    p.header.stamp =
        ros::Time((flags & 4) ? in.scaled(0, 8) : 1.0 + k * 0.5 + in.scaled(-0.3, 0.3));
    geometry_msgs::Point& t = p.pose.position;
    if (flags & 2) {
      t.x = in.f32(), t.y = in.f32(), t.z = in.f32();
    } else {
      t.x = in.scaled(-1, 1), t.y = in.scaled(-1, 1), t.z = in.scaled(-1, 1);
    }
    geometry_msgs::Quaternion& q = p.pose.orientation;
    if (flags & 1) {
      q.x = in.f32(), q.y = in.f32(), q.z = in.f32(), q.w = in.f32();
    } else {
      const Eigen::Vector3d axis_angle(in.scaled(-M_PI, M_PI), in.scaled(-M_PI, M_PI),
                                       in.scaled(-M_PI, M_PI));
      Eigen::Quaterniond r = Eigen::Quaterniond::Identity();
      if (axis_angle.norm() > 0)
        r = Eigen::Quaterniond(Eigen::AngleAxisd(axis_angle.norm(), axis_angle.normalized()));
      const double norm = in.scaled(0.98, 1.02);
      q.x = r.x() * norm, q.y = r.y() * norm, q.z = r.z() * norm, q.w = r.w() * norm;
    }
    path.poses.push_back(p);
  }
  std::vector<StampedPose> poses;
  std::string why;
  if (!toCameraPoses(path, Eigen::Isometry3d::Identity(), &poses, &why)) {
    fuzz::require(!why.empty());
    return 0;
  }
  for (const StampedPose& p : poses)
    fuzz::require(p.T_world_camera.matrix().allFinite() &&
                  std::abs(p.T_world_camera.linear().determinant() - 1.0) < 1e-6);

  MapperConfig config;
  config.num_threads = 1;
  config.histogram_min_points = 0;
  SessionConfig session_config;
  session_config.loop_closure_max_frames = kFrames;
  session_config.background_corrections = false;  // applied before submitTrajectory() returns
  MappingSession session(config, session_config);
  for (int i = 0; i < kFrames; ++i) session.fuse(frame(i), session.arrive(), MeshTiming::kNow);
  if (flags & 8) {
    session.clear(MapRegion::box({-0.3, -0.3, 1.8}, {0.3, 0.3, 2.2}), 2.5);
  }
  // Not a structured binding: lambdas may capture those only from C++20 (clang refuses).
  size_t blocks_before = 0, triangles_before = 0;
  session.read([&](const Mapper& m) {
    blocks_before = m.tsdf().blockCount();
    triangles_before = m.mesh().triangleCount();
  });

  const std::optional<CorrectionReport> report = session.submitTrajectory(std::move(poses));
  fuzz::require(report.has_value());
  fuzz::require(report->outcome < TrajectoryOutcome::kCount);
  const TrajectoryOutcomeInfo& info = trajectoryOutcomeInfo(report->outcome);
  session.withMap([&](MapAccess& access) {
    const Mapper& m = access.map();
    if (info.rejected || report->outcome == TrajectoryOutcome::kFailed) {
      fuzz::require(!report->message.empty());
      fuzz::require(m.tsdf().blockCount() == blocks_before);
      fuzz::require(m.mesh().triangleCount() == triangles_before);
    }
    access.updateMesh();
    fuzz::checkMesh(m.extractMesh());
  });
  return 0;
}
