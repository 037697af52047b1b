// Properties of the whole integrate() path that doc/design.md lists.
#include <gtest/gtest.h>

#include <set>

#include "MeshTestSupport.h"
#include "QuickMode.h"
#include "TestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

sim::AnalyticScene tableTop() {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0.4, 0}, {0, -1, 0}), {180, 160, 120});  // floor (y down)
  scene.add(sim::makeSphere({0.1, 0.1, 1.6}, 0.25), {200, 60, 60});
  Eigen::Isometry3d box = Eigen::Isometry3d::Identity();
  box.translate(Eigen::Vector3d(-0.4, 0.25, 1.9));
  box.rotate(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()));
  scene.add(sim::makeBox(box, {0.15, 0.15, 0.15}), {60, 200, 60});
  return scene;
}

std::vector<StereoFrame> orbitFrames(int n, double noise_px = 0.0,
                                     const StereoCamera& camera = vgaCamera()) {
  const sim::AnalyticScene scene = tableTop();
  std::vector<StereoFrame> frames;
  for (int f = 0; f < n; ++f) {
    const double a = -0.5 + f * 0.25;
    const Eigen::Vector3d eye(1.6 * std::sin(a), -0.3, 1.7 - 1.6 * std::cos(a));
    frames.push_back(renderFrame(scene, camera,
                                 sim::lookAt(eye, {0, 0.1, 1.7}, -Eigen::Vector3d::UnitY()),
                                 noise_px, 10 + f));
  }
  return frames;
}

}  // namespace

/// One orbit frame fused twice with `config`: the map and its level-0 zero crossings after
/// each pass.
struct FusedTwice {
  MapSnapshot once, twice;
  std::vector<Eigen::Vector3d> crossings_once, crossings_twice;
};

FusedTwice fuseOneFrameTwice(const MapperConfig& config) {
  Mapper mapper(config);
  const StereoFrame frame = orbitFrames(1, 0.3)[0];
  FusedTwice result;
  EXPECT_TRUE(mapper.integrate(frame).accepted);
  result.once = snapshot(mapper.tsdf());
  result.crossings_once = zeroCrossings(mapper.tsdf(), 0, 2);
  EXPECT_TRUE(mapper.integrate(frame).accepted);
  result.twice = snapshot(mapper.tsdf());
  result.crossings_twice = zeroCrossings(mapper.tsdf(), 0, 2);
  return result;
}

TEST(MapperProperties, FusingTheSameFrameTwiceWithRefinementKeepsEveryCrossing) {
  // With update_allocated_finer_level (the default) the second pass of the same frame also
  // lets its level-1 pixels update the level-0 voxels that its level-0 pixels allocated in the
  // first: every crossing of the first pass stays where it was and new ones may appear, no
  // block and no level is added.
  MapperConfig config;
  ASSERT_TRUE(config.update_allocated_finer_level);
  const FusedTwice fused = fuseOneFrameTwice(config);
  ASSERT_GT(fused.crossings_once.size(), 500u);
  EXPECT_GE(fused.crossings_twice.size(), fused.crossings_once.size());
  double worst = 0;
  for (const Eigen::Vector3d& p : fused.crossings_once) {
    double nearest = INFINITY;
    for (const Eigen::Vector3d& q : fused.crossings_twice)
      nearest = std::min(nearest, (p - q).norm());
    worst = std::max(worst, nearest);
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_EQ(fused.twice.keys, fused.once.keys);
  EXPECT_EQ(fused.twice.level_masks, fused.once.level_masks);
}

TEST(MapperProperties, FusingTheSameFrameTwiceKeepsTheSurface) {
  // With the thesis' level rule the second pass updates exactly the voxels of the first.
  // (update_allocated_finer_level lets the second pass also refine the level-0 voxels that
  // the first pass allocated: FusingTheSameFrameTwiceWithRefinementKeepsEveryCrossing.)
  MapperConfig config;
  config.update_allocated_finer_level = false;
  const FusedTwice fused = fuseOneFrameTwice(config);
  const auto& crossings_once = fused.crossings_once;
  const auto& crossings_twice = fused.crossings_twice;
  ASSERT_GT(crossings_once.size(), 500u);
  ASSERT_EQ(crossings_once.size(), crossings_twice.size());
  double worst = 0;
  for (size_t i = 0; i < crossings_once.size(); ++i)
    worst = std::max(worst, (crossings_once[i] - crossings_twice[i]).norm());
  EXPECT_LT(worst, 1e-6);  // float rounding of the average only
  // Same blocks, and every observed voxel's weight has grown (none exceeds the cap here).
  ASSERT_EQ(fused.twice.keys, fused.once.keys);
  EXPECT_EQ(fused.twice.level_masks, fused.once.level_masks);
  const std::vector<Voxel>& before = fused.once.voxels;
  const std::vector<Voxel>& after = fused.twice.voxels;
  size_t observed = 0;
  for (size_t i = 0; i < before.size(); ++i) {
    if (before[i].weight <= 0) continue;
    ++observed;
    EXPECT_GT(after[i].weight, before[i].weight);
  }
  EXPECT_GT(observed, 10000u);
}

TEST(MapperProperties, ThreadCountDoesNotChangeTheMap) {
  // Quick mode: two quarter-resolution frames instead of four VGA ones.
  const std::vector<StereoFrame> frames =
      quickMode()
          ? orbitFrames(2, 0.3, *StereoCamera::create(160, 120, 131.25, 131.25, 79.5, 59.5, 0.1))
          : orbitFrames(4, 0.3);
  std::optional<MapSnapshot> reference;
  for (int threads : {1, 2, 4}) {
    for (LookupMode mode : {LookupMode::kAccelerated, LookupMode::kNaive}) {
      MapperConfig config;
      config.num_threads = threads;
      config.lookup_mode = mode;
      Mapper mapper(config);
      for (const StereoFrame& f : frames) ASSERT_TRUE(mapper.integrate(f).accepted);
      const MapSnapshot s = snapshot(mapper.tsdf());
      if (!reference) {
        reference = s;
        EXPECT_GT(s.keys.size(), 500u) << "blocks";
      } else {
        EXPECT_TRUE(s == *reference) << threads << " threads: maps differ";
      }
    }
  }
}

TEST(MapperProperties, IntegrationReportsTimingsAndCounts) {
  Mapper mapper(MapperConfig{});
  const IntegrationResult r = mapper.integrate(orbitFrames(1)[0]);
  ASSERT_TRUE(r.accepted);
  EXPECT_TRUE(r.error.empty());
  EXPECT_GT(r.lookup.valid_points, 100000u);
  EXPECT_GT(r.lookup.blocks_queued, 100u);
  // The lookup allocates nothing; fusion creates exactly the blocks it updated, on an empty map
  // all of them, and the rest of what the bands reached is never allocated.
  EXPECT_EQ(r.lookup.blocks_allocated, 0u);
  EXPECT_EQ(r.lookup.blocks_missing, r.lookup.blocks_queued);
  EXPECT_EQ(r.fusion.blocks_created, mapper.tsdf().blockCount());
  EXPECT_EQ(r.fusion.blocks_created + r.fusion.blocks_not_created, r.lookup.blocks_missing);
  EXPECT_GT(r.fusion.blocks_not_created, 0u);
  size_t voxel_bytes = 0;
  for (const VoxelBlock* b : mapper.tsdf().blocks()) voxel_bytes += b->voxelBytes();
  EXPECT_EQ(r.fusion.level_bytes_allocated, voxel_bytes);
  EXPECT_GT(r.fusion.voxels_updated, r.lookup.blocks_queued);
  EXPECT_EQ(r.updated_blocks.size(), r.fusion.blocks_updated);
  EXPECT_TRUE(std::is_sorted(r.updated_blocks.begin(), r.updated_blocks.end()));
  EXPECT_GE(r.lookup_ms, 0.0);
  EXPECT_GE(r.fusion_ms, 0.0);
  EXPECT_EQ(mapper.framesIntegrated(), 1u);
  mapper.reset();
  EXPECT_EQ(mapper.tsdf().blockCount(), 0u);
}

TEST(MapperProperties, NonFiniteDisparityPixelsAreSkippedLikeInvalidOnes) {
  // Replacing invalid (0) pixels by NaN, ±inf or negative values must change nothing.
  StereoFrame clean = orbitFrames(1)[0];
  for (int v = 0; v < clean.disparity_px.rows; v += 3)
    for (int u = v % 7; u < clean.disparity_px.cols; u += 5)
      clean.disparity_px.at<float>(v, u) = 0.0f;
  StereoFrame dirty = clean;
  dirty.disparity_px = clean.disparity_px.clone();
  const float bad[] = {NAN, INFINITY, -INFINITY, -3.0f};
  int n = 0;
  for (int v = 0; v < dirty.disparity_px.rows; ++v)
    for (int u = 0; u < dirty.disparity_px.cols; ++u)
      if (dirty.disparity_px.at<float>(v, u) == 0.0f)
        dirty.disparity_px.at<float>(v, u) = bad[n++ % 4];
  ASSERT_GT(n, 10000);
  Mapper a(MapperConfig{}), b(MapperConfig{});
  const IntegrationResult ra = a.integrate(clean);
  const IntegrationResult rb = b.integrate(dirty);
  ASSERT_TRUE(ra.accepted && rb.accepted);
  EXPECT_EQ(ra.lookup.valid_points, rb.lookup.valid_points);
  EXPECT_TRUE(snapshot(a.tsdf()) == snapshot(b.tsdf()));
}

TEST(MapperProperties, RejectedFramesLeaveTheMapUnchanged) {
  const std::vector<StereoFrame> frames = orbitFrames(2);
  Mapper mapper(MapperConfig{});
  ASSERT_TRUE(mapper.integrate(frames[0]).accepted);
  const MapSnapshot before = snapshot(mapper.tsdf());

  struct Case {
    const char* name;
    std::function<void(StereoFrame*)> corrupt;
    const char* message;
  };
  const std::vector<Case> cases = {
      {"colour size differs", [](StereoFrame* f) { f->color = cv::Mat(240, 320, CV_8UC3); },
       "colour image is 320x240"},
      {"disparity size differs from camera",
       [](StereoFrame* f) { f->disparity_px = cv::Mat(10, 10, CV_32FC1, cv::Scalar(5)); },
       "disparity is 10x10"},
      {"disparity wrong type",
       [](StereoFrame* f) { f->disparity_px.convertTo(f->disparity_px, CV_16UC1); }, "CV_32FC1"},
      {"empty disparity", [](StereoFrame* f) { f->disparity_px = cv::Mat(); }, "empty"},
      {"colour wrong type", [](StereoFrame* f) { f->color.convertTo(f->color, CV_32FC3); },
       "8-bit"},
      {"NaN in pose", [](StereoFrame* f) { f->T_world_camera.translation().x() = NAN; },
       "not finite"},
      {"inf in rotation", [](StereoFrame* f) { f->T_world_camera.linear()(0, 1) = INFINITY; },
       "not finite"},
      {"non-orthonormal rotation", [](StereoFrame* f) { f->T_world_camera.linear() *= 1.1; },
       "not a rotation"},
      {"reflection", [](StereoFrame* f) { f->T_world_camera.linear().col(0) *= -1; },
       "not a rotation"},
      {"pose beyond the map", [](StereoFrame* f) { f->T_world_camera.translation().x() = 1e9; },
       "beyond the map"},
      {"no camera", [](StereoFrame* f) { f->camera = StereoCamera(); }, "camera"},
  };
  for (const Case& c : cases) {
    StereoFrame bad = frames[1];
    bad.disparity_px = frames[1].disparity_px.clone();
    bad.color = frames[1].color.clone();
    c.corrupt(&bad);
    const IntegrationResult r = mapper.integrate(bad);
    EXPECT_FALSE(r.accepted) << c.name;
    EXPECT_NE(r.error.find(c.message), std::string::npos) << c.name << ": " << r.error;
    EXPECT_TRUE(snapshot(mapper.tsdf()) == before) << c.name << " changed the map";
  }
  EXPECT_EQ(mapper.framesIntegrated(), 1u);
  // A good frame is still accepted afterwards.
  EXPECT_TRUE(mapper.integrate(frames[1]).accepted);
}

TEST(MapperProperties, GreyImagesAndMissingColourAreAccepted) {
  StereoFrame frame = orbitFrames(1)[0];
  cv::Mat grey(frame.color.size(), CV_8UC1, cv::Scalar(77));
  frame.color = grey;
  Mapper mapper(MapperConfig{});
  ASSERT_TRUE(mapper.integrate(frame).accepted);
  for (const VoxelBlock* b : mapper.tsdf().blocks())
    for (int n = 0; n < VoxelBlock::kVoxelCount; ++n)
      if (const Voxel& v = b->voxel(n); v.weight > 0) {
        ASSERT_TRUE(v.r == 77 && v.g == 77 && v.b == 77);
      }
  frame.color = cv::Mat();
  EXPECT_TRUE(mapper.integrate(frame).accepted);
}

TEST(MapperProperties, InvalidConfigurationIsRefusedWithEveryReason) {
  MapperConfig config;
  config.voxel_size_m = -1;
  config.min_depth_m = 10;
  config.max_depth_m = 5;
  try {
    Mapper mapper(config);
    FAIL() << "constructor accepted an invalid configuration";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("voxel_size_m"), std::string::npos) << what;
    EXPECT_NE(what.find("min_depth_m must be < max_depth_m"), std::string::npos) << what;
  }
}

// Meshing at its own rate: frames fused with the mesh deferred and one updateMesh() at the end
// give the same map and the same mesh as meshing after every frame, and that mesh equals a
// from-scratch extraction. A pass with nothing changed does nothing.
TEST(MapperProperties, DeferredMeshingEqualsMeshingEveryFrameAndABatchRebuild) {
  const std::vector<StereoFrame> frames =
      orbitFrames(4, 0.3, *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1));
  MapperConfig config;
  Mapper every_frame(config), deferred(config);
  for (const StereoFrame& frame : frames) {
    ASSERT_TRUE(every_frame.integrate(frame).accepted);
    const IntegrationResult r = deferred.integrate(frame, MeshTiming::kDeferred);
    ASSERT_TRUE(r.accepted);
    EXPECT_EQ(r.mesh.blocks_meshed, 0u);
    EXPECT_TRUE(r.mesh.changed.empty());
  }
  EXPECT_GT(deferred.blocksAwaitingMesh(), 0u);
  EXPECT_TRUE(deferred.mesh().submeshes().empty());
  const MeshPass pass = deferred.updateMesh();
  EXPECT_GT(pass.blocks_changed, 100u);
  EXPECT_EQ(pass.mesh.changed.size(), deferred.mesh().submeshes().size());
  EXPECT_EQ(deferred.blocksAwaitingMesh(), 0u);
  EXPECT_TRUE(snapshot(deferred.tsdf()) == snapshot(every_frame.tsdf()));
  EXPECT_TRUE(triangleSets(deferred.mesh()) == triangleSets(every_frame.mesh()));
  expectMeshEqualsRebuild(deferred);
  const MeshPass idle = deferred.updateMesh();
  EXPECT_EQ(idle.blocks_changed, 0u);
  EXPECT_EQ(idle.mesh.blocks_meshed, 0u);
}

// The mesh's consumers (the nodelet's publisher is one) see every submesh change once, whatever
// their rate: a consumer that takes after every second pass holds exactly the current mesh.
TEST(MapperProperties, MeshChangeConsumersFollowTheMeshAtTheirOwnRate) {
  const std::vector<StereoFrame> frames =
      orbitFrames(5, 0.3, *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1));
  Mapper mapper(MapperConfig{});
  const BlockChangeLog::Consumer publisher = mapper.subscribeToMeshChanges("test publisher");
  std::set<BlockKey> held;
  for (size_t f = 0; f < frames.size(); ++f) {
    ASSERT_TRUE(mapper.integrate(frames[f]).accepted);
    if (f % 2 == 0) continue;
    const BlockChangeLog::Changes c = mapper.takeMeshChanges(publisher);
    for (const BlockKey& k : c.updated) held.insert(k);
    for (const BlockKey& k : c.erased) held.erase(k);
  }
  const BlockChangeLog::Changes rest = mapper.takeMeshChanges(publisher);
  for (const BlockKey& k : rest.updated) held.insert(k);
  for (const BlockKey& k : rest.erased) held.erase(k);
  std::set<BlockKey> current;
  for (const auto& [key, submesh] : mapper.mesh().submeshes()) current.insert(key);
  EXPECT_EQ(held, current);
  EXPECT_GT(current.size(), 50u);
  // A reset reports every submesh as gone.
  mapper.reset();
  EXPECT_EQ(mapper.takeMeshChanges(publisher).erased.size(), current.size());
}
