// PoseCorrection: the corrections a SLAM's revised trajectory implies for frames fused at their
// original poses, worked by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "stereo_fusion/trajectory/PoseCorrection.h"

using namespace stereo_fusion;

namespace {

Eigen::Isometry3d pose(double x, double y, double z, double yaw_deg = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() =
      Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

double yawDeg(const Eigen::Isometry3d& T) { return std::atan2(T(1, 0), T(0, 0)) * 180.0 / M_PI; }

/// Frames at t = 0, 1, ..., 4 s moving 1 m along x per second, unrotated.
std::vector<StampedPose> straightLine() {
  std::vector<StampedPose> fused;
  for (int i = 0; i < 5; ++i) fused.push_back({double(i), pose(i, 0, 0)});
  return fused;
}

}  // namespace

TEST(PoseCorrection, InterpolatePoseLerpsTranslationAndSlerpsRotation) {
  const Eigen::Isometry3d mid = interpolatePose(pose(0, 0, 0, 0), pose(2, 4, 0, 90), 0.5);
  EXPECT_NEAR(mid.translation().x(), 1.0, 1e-12);
  EXPECT_NEAR(mid.translation().y(), 2.0, 1e-12);
  EXPECT_NEAR(yawDeg(mid), 45.0, 1e-9);
  EXPECT_NEAR(yawDeg(interpolatePose(pose(0, 0, 0, 0), pose(0, 0, 0, 90), 0.25)), 22.5, 1e-9);
}

TEST(PoseCorrection, OriginalPoseBetweenFramesIsInterpolatedAndFarStampsHaveNone) {
  const std::vector<StampedPose> fused = straightLine();
  Eigen::Isometry3d p;
  ASSERT_TRUE(originalPoseAt(fused, 2.25, 0.5, &p));
  EXPECT_NEAR(p.translation().x(), 2.25, 1e-12);
  ASSERT_TRUE(originalPoseAt(fused, 4.4, 0.5, &p));  // within 0.5 s after the last frame: the last
  EXPECT_NEAR(p.translation().x(), 4.0, 1e-12);
  EXPECT_FALSE(originalPoseAt(fused, 4.6, 0.5, &p));
  EXPECT_FALSE(originalPoseAt(fused, -0.6, 0.5, &p));
  EXPECT_FALSE(originalPoseAt({}, 1.0, 0.5, &p));
}

TEST(PoseCorrection, ATrajectoryThatAgreesCorrectsNothing) {
  const std::vector<StampedPose> fused = straightLine();
  const PoseCorrection correction(fused, {fused[0], fused[2], fused[4]}, 4.0);
  ASSERT_EQ(correction.corrections().size(), 3u);
  for (const StampedPose& f : fused)
    EXPECT_TRUE(
        correction.corrected(f.stamp_s, f.T_world_camera).isApprox(f.T_world_camera, 1e-12));
}

TEST(PoseCorrection, FramesBetweenTrajectoryPosesTakeTheInterpolatedCorrectionHandWorked) {
  const std::vector<StampedPose> fused = straightLine();
  // At t = 0 the SLAM moves the frame by +1 m in y; at t = 4 by +3 m in y and 90° of yaw.
  const std::vector<StampedPose> trajectory{{0.0, pose(0, 1, 0)},
                                            {4.0, pose(4, 3, 0) * pose(0, 0, 0, 90)}};
  const PoseCorrection correction(fused, trajectory, 4.0);
  ASSERT_EQ(correction.corrections().size(), 2u);
  // C_0 = T_0 · O(0)⁻¹ = translation (0, 1, 0). C_4 = T_4 · O(4)⁻¹: rotate by 90° about the
  // z axis through (4, 3, 0), i.e. R(90°) with translation (4, 3) − R(90°)·(4, 0) = (4, −1).
  const Eigen::Isometry3d c4 = correction.corrections()[1].T_world_camera;
  EXPECT_NEAR(yawDeg(c4), 90.0, 1e-9);
  EXPECT_NEAR(c4.translation().x(), 4.0, 1e-9);
  EXPECT_NEAR(c4.translation().y(), -1.0, 1e-9);
  // Frame t = 2: C = halfway, 45° and translation (2, 0) applied to O(2) = (2, 0, 0):
  // R(45°)·(2, 0) + (2, 0) = (2 + √2, √2).
  const Eigen::Isometry3d at2 = correction.corrected(2.0, fused[2].T_world_camera);
  EXPECT_NEAR(yawDeg(at2), 45.0, 1e-9);
  EXPECT_NEAR(at2.translation().x(), 2.0 + std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(at2.translation().y(), std::sqrt(2.0), 1e-9);
  // The trajectory poses themselves are met exactly.
  EXPECT_TRUE(correction.corrected(4.0, fused[4].T_world_camera)
                  .isApprox(trajectory[1].T_world_camera, 1e-12));
  EXPECT_TRUE(correction.corrected(0.0, fused[0].T_world_camera)
                  .isApprox(trajectory[0].T_world_camera, 1e-12));
}

TEST(PoseCorrection, BeforeTheFirstPoseTheFirstCorrectionAfterTheLastOnlyForFramesFusedBeforeIt) {
  std::vector<StampedPose> fused = straightLine();
  const std::vector<StampedPose> trajectory{{1.0, pose(1, 0.5, 0)}, {2.0, pose(2, 0.5, 0)}};
  // The trajectory arrived when frame t = 3 had been fused: frame 3 shares the drift, frame 4
  // came later with a pose already corrected by the SLAM.
  const PoseCorrection correction(fused, trajectory, 3.0);
  EXPECT_NEAR(correction.corrected(0.0, fused[0].T_world_camera).translation().y(), 0.5, 1e-12);
  EXPECT_NEAR(correction.corrected(3.0, fused[3].T_world_camera).translation().y(), 0.5, 1e-12);
  EXPECT_NEAR(correction.corrected(4.0, fused[4].T_world_camera).translation().y(), 0.0, 1e-12);
}

TEST(PoseCorrection, TrajectoryPosesFarFromEveryFusedFrameAreSkipped) {
  const std::vector<StampedPose> fused = straightLine();
  const PoseCorrection correction(fused, {{10.0, pose(0, 5, 0)}, {-3.0, pose(0, 5, 0)}}, 4.0);
  EXPECT_TRUE(correction.empty());
  EXPECT_TRUE(correction.correctionAt(2.0).isApprox(Eigen::Isometry3d::Identity()));
}
