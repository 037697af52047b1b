// The bad-input catalogue (doc/reliability.md, "Bad input") cases of the Mapper not covered
// elsewhere: time order, duplicates and pose jumps, degenerate disparity values. Each checks the
// message, the counter or reason, and that the map and mesh did not change. The cases of ROS
// messages and bags are in test/unit/ros/test_bad_input_ros.cpp.
#include <gtest/gtest.h>

#include <cfloat>
#include <opencv2/core.hpp>

#include "MeshTestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

/// The map and the mesh, for before/after comparisons.
struct MapState {
  MapSnapshot map;
  std::map<BlockKey, std::multiset<std::array<float, 9>>> mesh;
  bool operator==(const MapState& o) const { return map == o.map && mesh == o.mesh; }
};
MapState state(const Mapper& m) { return {snapshot(m.tsdf()), triangleSets(m.mesh())}; }

/// Frame 1 of floorAndSphereFrame() with disparities drawn uniformly over 1–64 px (a broken
/// matcher): a point anywhere along every ray.
StereoFrame randomDisparityFrame() {
  StereoFrame noise = floorAndSphereFrame(1, 2.0);
  cv::RNG rng(7);
  rng.fill(noise.disparity_px, cv::RNG::UNIFORM, 1.0, 64.0);
  return noise;
}

/// Integrates `frame`, which must be rejected for `reason` with the map (state and memory) as it
/// was; returns the result for its message.
IntegrationResult expectRejectedMapUnchanged(Mapper* mapper, const StereoFrame& frame,
                                             RejectReason reason, const char* reason_name) {
  const MapState before = state(*mapper);
  const size_t bytes_before = mapper->memoryBytes();
  const IntegrationResult rejected = mapper->integrate(frame);
  EXPECT_FALSE(rejected.accepted);
  EXPECT_EQ(rejected.reason, reason);
  EXPECT_STREQ(rejectReasonName(rejected.reason), reason_name);
  EXPECT_TRUE(rejected.updated_blocks.empty());
  EXPECT_TRUE(state(*mapper) == before) << "a rejected frame changed the map";
  EXPECT_EQ(mapper->memoryBytes(), bytes_before);
  return rejected;
}
}  // namespace

TEST(BadInput, TimestampsGoingBackwardsAndDuplicatesAreRejectedByReason) {
  Mapper mapper(MapperConfig{});
  ASSERT_TRUE(mapper.integrate(floorAndSphereFrame(0, 10.0)).accepted);
  ASSERT_TRUE(mapper.integrate(floorAndSphereFrame(1, 10.5)).accepted);
  const MapState before = state(mapper);

  IntegrationResult r = mapper.integrate(floorAndSphereFrame(2, 10.2));
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(r.reason, RejectReason::kTimestampBackwards);
  EXPECT_EQ(r.error, "timestamp 10.2 s goes backwards (last fused frame at 10.5 s)");
  EXPECT_STREQ(rejectReasonName(r.reason), "timestamp_backwards");
  EXPECT_TRUE(state(mapper) == before);

  r = mapper.integrate(floorAndSphereFrame(1, 10.5));  // the same frame delivered twice
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(r.reason, RejectReason::kDuplicateTimestamp);
  EXPECT_EQ(r.error, "duplicate frame: timestamp 10.5 s was already fused");
  EXPECT_STREQ(rejectReasonName(r.reason), "duplicate");
  EXPECT_TRUE(state(mapper) == before);
  EXPECT_EQ(mapper.framesIntegrated(), 2u);

  // Time 0 is "unknown" and never ordered; a later stamp is accepted again.
  EXPECT_TRUE(mapper.integrate(floorAndSphereFrame(2, 0.0)).accepted);
  EXPECT_TRUE(mapper.integrate(floorAndSphereFrame(3, 11.0)).accepted);
  // The check can be switched off; reset() forgets the history.
  MapperConfig lax;
  lax.require_increasing_timestamps = false;
  Mapper relaxed(lax);
  EXPECT_TRUE(relaxed.integrate(floorAndSphereFrame(0, 10.0)).accepted);
  EXPECT_TRUE(relaxed.integrate(floorAndSphereFrame(1, 9.0)).accepted);
  mapper.reset();
  EXPECT_TRUE(mapper.integrate(floorAndSphereFrame(0, 1.0)).accepted);
}

TEST(BadInput, PoseJumpsAreJudgedAgainstTheLastFusedFrameAndARelocalisationCostsTwoFrames) {
  Mapper mapper(MapperConfig{});  // max_pose_jump_m = 100
  ASSERT_TRUE(mapper.integrate(floorAndSphereFrame(0, 1.0)).accepted);
  const MapState before = state(mapper);
  StereoFrame glitch = floorAndSphereFrame(1, 2.0);
  glitch.T_world_camera.translation() += Eigen::Vector3d(3000.0, 0, 0);
  IntegrationResult r = mapper.integrate(glitch);
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(r.reason, RejectReason::kPoseJump);
  EXPECT_NE(r.error.find("camera jumped 3000"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("since the last fused frame (max_pose_jump_m = 100)"), std::string::npos)
      << r.error;
  EXPECT_TRUE(state(mapper) == before);
  // The glitch did not become the reference: the next good frame is fused.
  r = mapper.integrate(floorAndSphereFrame(1, 3.0));
  EXPECT_TRUE(r.accepted) << r.error;
  EXPECT_FALSE(r.reanchored);
  // Glitches that do not agree with each other never take over, however many there are.
  for (int k = 0; k < 6; ++k) {
    StereoFrame wild = floorAndSphereFrame(2, 4.0 + k);
    wild.T_world_camera.translation() += Eigen::Vector3d(k % 2 ? -2000.0 : 2000.0, 300.0 * k, 0);
    EXPECT_EQ(mapper.integrate(wild).reason, RejectReason::kPoseJump) << k;
  }
  EXPECT_TRUE(mapper.integrate(floorAndSphereFrame(2, 10.0)).accepted);
  // A lasting relocalisation: two frames lost, the third that agrees with them is fused and
  // becomes the reference.
  const MapState before_relocalisation = state(mapper);
  for (int k = 0; k < FrameGate::kFramesToReanchor; ++k) {
    StereoFrame moved = floorAndSphereFrame(3, 11.0 + k);
    moved.T_world_camera.translation() += Eigen::Vector3d(0, 0.01 * k, 500.0);
    r = mapper.integrate(moved);
    if (k + 1 < FrameGate::kFramesToReanchor) {
      EXPECT_EQ(r.reason, RejectReason::kPoseJump) << k;
      EXPECT_TRUE(state(mapper) == before_relocalisation) << k;
    }
  }
  EXPECT_TRUE(r.accepted) << r.error;
  EXPECT_TRUE(r.reanchored);
  EXPECT_NE(r.note.find("agree with each other"), std::string::npos) << r.note;
  StereoFrame next = floorAndSphereFrame(4, 20.0);
  next.T_world_camera.translation() += Eigen::Vector3d(0, 0, 500.0);
  EXPECT_TRUE(mapper.integrate(next).accepted);
  // 0 disables the check.
  MapperConfig off;
  off.max_pose_jump_m = 0;
  Mapper unchecked(off);
  EXPECT_TRUE(unchecked.integrate(floorAndSphereFrame(0, 1.0)).accepted);
  EXPECT_TRUE(unchecked.integrate(glitch).accepted);
}

TEST(BadInput, AStampFarInTheFutureCostsOneFrameAndAClockResetThree) {
  Mapper mapper(MapperConfig{});  // max_timestamp_gap_s = 3600
  ASSERT_TRUE(mapper.integrate(floorAndSphereFrame(0, 100.0)).accepted);
  const MapState before = state(mapper);
  IntegrationResult r = mapper.integrate(floorAndSphereFrame(1, 1e9));
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(r.reason, RejectReason::kTimestampJump);
  EXPECT_STREQ(rejectReasonName(r.reason), "timestamp_jump");
  EXPECT_NE(r.error.find("after the last fused frame (max_timestamp_gap_s = 3600)"),
            std::string::npos)
      << r.error;
  EXPECT_TRUE(state(mapper) == before);
  // Later good frames are not "backwards" from the bad stamp: they are fused.
  for (int k = 0; k < 5; ++k)
    EXPECT_TRUE(mapper.integrate(floorAndSphereFrame(1 + k % 3, 101.0 + k)).accepted) << k;
  // A clock that really went back (a new recording, a restarted driver): after three frames
  // that follow each other, the gate follows the new clock.
  for (int k = 0; k < FrameGate::kFramesToReanchor; ++k) {
    r = mapper.integrate(floorAndSphereFrame(k % 3, 5.0 + 0.1 * k));
    EXPECT_EQ(r.accepted, k + 1 == FrameGate::kFramesToReanchor) << k << " " << r.error;
  }
  EXPECT_TRUE(r.reanchored);
  EXPECT_TRUE(mapper.integrate(floorAndSphereFrame(1, 5.5)).accepted);
  // Frames stamped after one bad past stamp do not agree with it: a lone stamp never takes over.
  EXPECT_EQ(mapper.integrate(floorAndSphereFrame(2, 1.0)).reason,
            RejectReason::kTimestampBackwards);
  EXPECT_TRUE(mapper.integrate(floorAndSphereFrame(2, 5.6)).accepted);
}

TEST(BadInput, DegenerateDisparityValuesLeaveTheMapUnchanged) {
  Mapper mapper(MapperConfig{});
  ASSERT_TRUE(mapper.integrate(floorAndSphereFrame(0, 1.0)).accepted);
  const MapState before = state(mapper);
  struct Case {
    const char* name;
    float value;
  };
  // Huge disparities mean a depth below min_depth_m (f·b/d → 0); the rest are invalid.
  const Case cases[] = {{"NaN", NAN},
                        {"+inf", INFINITY},
                        {"-inf", -INFINITY},
                        {"negative", -5.0f},
                        {"huge", 1e30f},
                        {"FLT_MAX", FLT_MAX},
                        {"all zero (all invalid)", 0.0f}};
  double t = 2.0;
  for (const Case& c : cases) {
    StereoFrame f = floorAndSphereFrame(1, t += 1.0);
    f.disparity_px.setTo(c.value);
    const IntegrationResult r = mapper.integrate(f);
    EXPECT_TRUE(r.accepted) << c.name << ": valid input with nothing in it";
    EXPECT_EQ(r.lookup.valid_points, 0u) << c.name;
    EXPECT_TRUE(r.updated_blocks.empty()) << c.name;
    EXPECT_TRUE(state(mapper) == before) << c.name << " changed the map";
  }
}

// Random disparities put a point anywhere along every ray: each pixel reaches its own blocks, so
// the frame's bands reach far more new blocks than a surface does. Over the budget the frame is
// rejected before fusion; at exactly the budget it is fused.
TEST(BadInput, AFrameOverItsAllocationBudgetIsRejectedAndTheMapUnchanged) {
  MapperConfig config;
  config.histogram_min_points = 0;        // every pixel reaches the map: the bound alone must hold
  config.min_coherent_pixel_share = 0.0;  // the coherence check would reject the noise first
  const StereoFrame noise = randomDisparityFrame();

  // How many new blocks the noise frame reaches after the first good frame, with no limit.
  size_t reached = 0;
  {
    config.max_new_blocks_per_frame = 0;
    Mapper unlimited(config);
    ASSERT_TRUE(unlimited.integrate(floorAndSphereFrame(0, 1.0)).accepted);
    const IntegrationResult r = unlimited.integrate(noise);
    ASSERT_TRUE(r.accepted);
    reached = r.lookup.blocks_missing;
    EXPECT_GT(r.fusion.blocks_created, 1000u)
        << "noise must allocate much more than the budget below";
  }
  ASSERT_GT(reached, 0u);

  config.max_new_blocks_per_frame = static_cast<int>(reached) - 1;
  Mapper mapper(config);
  ASSERT_TRUE(mapper.integrate(floorAndSphereFrame(0, 1.0)).accepted);
  const IntegrationResult rejected = expectRejectedMapUnchanged(
      &mapper, noise, RejectReason::kAllocationBudget, "allocation_budget");
  EXPECT_NE(rejected.error.find("reach " + std::to_string(reached) +
                                " blocks not yet in the map, more than "
                                "max_new_blocks_per_frame (" +
                                std::to_string(reached - 1) + ")"),
            std::string::npos)
      << rejected.error;

  // The rejected frame did not become the time reference: a good frame stamped before it is fused.
  const IntegrationResult good = mapper.integrate(floorAndSphereFrame(2, 1.5));
  EXPECT_TRUE(good.accepted) << good.error;
  EXPECT_FALSE(good.updated_blocks.empty());

  // At exactly the budget the frame is fused.
  config.max_new_blocks_per_frame = static_cast<int>(reached);
  Mapper at_budget(config);
  ASSERT_TRUE(at_budget.integrate(floorAndSphereFrame(0, 1.0)).accepted);
  EXPECT_TRUE(at_budget.integrate(noise).accepted);
}

// The absurd-calibration class: a frame whose bands would make the lookup visit more blocks than
// max_lookup_blocks_per_frame is dropped after one pass over its pixels, before any block is
// visited, and counted under its own reason.
TEST(BadInput, AFrameOverTheLookupWorkBoundIsRejectedAndTheMapUnchanged) {
  MapperConfig config;
  const StereoFrame frame = floorAndSphereFrame(1, 2.0);
  uint64_t work = 0;
  {
    Mapper unlimited(config);
    const IntegrationResult r = unlimited.integrate(frame);
    ASSERT_TRUE(r.accepted) << r.error;
    work = r.lookup.box_blocks;
  }
  ASSERT_GT(work, 100u);
  config.max_lookup_blocks_per_frame = static_cast<int>(work) - 1;
  Mapper mapper(config);
  const IntegrationResult rejected =
      expectRejectedMapUnchanged(&mapper, frame, RejectReason::kWorkBound, "work_bound");
  EXPECT_TRUE(rejected.lookup.over_work_bound);
  EXPECT_EQ(rejected.lookup.octree_searches, 0u);
  EXPECT_NE(rejected.error.find("span " + std::to_string(work) +
                                " blocks for the lookup to visit, more than "
                                "max_lookup_blocks_per_frame (" +
                                std::to_string(work - 1) + ")"),
            std::string::npos)
      << rejected.error;
  EXPECT_STREQ(rejectReasonInfo(RejectReason::kWorkBound).label, "dropped: lookup work bound");
  // The rejected frame did not become the time reference, and at the bound it is fused.
  config.max_lookup_blocks_per_frame = static_cast<int>(work);
  Mapper at_bound(config);
  EXPECT_TRUE(at_bound.integrate(frame).accepted);
}

// Random disparities agree with their neighbours only by chance (about 12 % over 1–64 px);
// a matcher's output almost always. Below min_coherent_pixel_share the frame is rejected before
// the lookup, whatever its allocation, and the map stays as it was.
TEST(BadInput, RandomDisparitiesAreRejectedAsIncoherentAndTheMapUnchanged) {
  MapperConfig config;
  const StereoFrame noise = randomDisparityFrame();
  Mapper mapper(config);
  ASSERT_TRUE(mapper.integrate(floorAndSphereFrame(0, 1.0)).accepted);
  const IntegrationResult rejected = expectRejectedMapUnchanged(
      &mapper, noise, RejectReason::kIncoherentDisparity, "incoherent_disparity");
  EXPECT_NE(
      rejected.error.find("usable disparities agree within 0.5 px with a neighbour, less than "
                          "min_coherent_pixel_share (50.0 %)"),
      std::string::npos)
      << rejected.error;
  // Not the time reference: a good frame stamped before it is fused.
  EXPECT_TRUE(mapper.integrate(floorAndSphereFrame(2, 1.5)).accepted);

  // With the check off the same frame is fused (the budget is then the only bound).
  config.min_coherent_pixel_share = 0.0;
  Mapper unchecked(config);
  ASSERT_TRUE(unchecked.integrate(floorAndSphereFrame(0, 1.0)).accepted);
  EXPECT_TRUE(unchecked.integrate(noise).accepted);
  // A noisy real surface (0.3 px) is fused with the default.
  Mapper noisy(MapperConfig{});
  StereoFrame surface = renderFrame(floorAndSphere(), qvgaCamera(), floorAndSphereView(1), 0.3, 5);
  surface.timestamp_s = 1.0;
  EXPECT_TRUE(noisy.integrate(surface).accepted);
}
