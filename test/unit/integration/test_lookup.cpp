#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "TestSupport.h"
#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/integration/BlockLookup.h"
#include "stereo_fusion/integration/SurfaceFuser.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

std::vector<std::tuple<int, int, int>> keysOf(const std::vector<VoxelBlock*>& blocks) {
  std::vector<std::tuple<int, int, int>> keys;
  for (const VoxelBlock* b : blocks) keys.emplace_back(b->key.x, b->key.y, b->key.z);
  return keys;
}

sim::AnalyticScene planeAndSphere() {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 3.0}, {0.2, -0.1, -1.0}));
  scene.add(sim::makeSphere({0.3, 0.1, 1.4}, 0.35));
  return scene;
}

struct LookupRun {
  std::vector<VoxelBlock*> queue;
  LookupStats stats;
};

LookupRun runLookup(const MapperConfig& config, const StereoFrame& frame, BlockOctree* tree) {
  ThreadPool pool(config.num_threads);
  BlockLookup lookup(stageConfigs(config).pipeline.lookup, &pool);
  LookupRun run;
  MeasurementImage measurements;
  measurements.build(frame, stageConfigs(config).pipeline.measurement, &pool);
  run.stats = lookup.run(frame, measurements, tree, &run.queue);
  return run;
}

/// `frame` through the naive lookup into `naive_tree` and the accelerated one into `accel_tree`.
struct NaiveAndAccelerated {
  LookupRun naive, accel;
};
NaiveAndAccelerated runNaiveAndAccelerated(MapperConfig config, const StereoFrame& frame,
                                           BlockOctree* naive_tree, BlockOctree* accel_tree) {
  NaiveAndAccelerated runs;
  config.lookup_mode = LookupMode::kNaive;
  runs.naive = runLookup(config, frame, naive_tree);
  config.lookup_mode = LookupMode::kAccelerated;
  runs.accel = runLookup(config, frame, accel_tree);
  return runs;
}

/// A frame in which every pixel sees the same depth (a fronto-parallel plane).
StereoFrame constantDepthFrame(const StereoCamera& camera, float disparity) {
  StereoFrame frame;
  frame.camera = camera;
  frame.disparity_px = cv::Mat(camera.height(), camera.width(), CV_32FC1, cv::Scalar(disparity));
  return frame;
}

/// True if this CPU runs the AVX2 lookup (the scalar one is then its reference).
bool lookupUsesSimd() {
  MapperConfig config;
  ThreadPool pool(1);
  return BlockLookup(stageConfigs(config).pipeline.lookup, &pool).usesSimd();
}

/// The scalar and the AVX2 lookup on the same frame, each into its own octree.
struct ScalarAndVector {
  LookupStats scalar, vector;
  std::vector<std::tuple<int, int, int>> scalar_keys, vector_keys;
};

ScalarAndVector runScalarAndVector(const MapperConfig& config, const StereoFrame& frame,
                                   ThreadPool* pool) {
  BlockOctree scalar_tree(config.blockSizeM()), vector_tree(config.blockSizeM());
  BlockLookup scalar(stageConfigs(config).pipeline.lookup, pool, /*allow_simd=*/false),
      vector(stageConfigs(config).pipeline.lookup, pool);
  EXPECT_FALSE(scalar.usesSimd());
  std::vector<VoxelBlock*> scalar_queue, vector_queue;
  ScalarAndVector r;
  MeasurementImage measurements;
  measurements.build(frame, stageConfigs(config).pipeline.measurement, pool);
  r.scalar = scalar.run(frame, measurements, &scalar_tree, &scalar_queue);
  r.vector = vector.run(frame, measurements, &vector_tree, &vector_queue);
  r.scalar_keys = keysOf(scalar_queue);
  r.vector_keys = keysOf(vector_queue);
  return r;
}
}  // namespace

TEST(BlockLookup, NaiveAndAcceleratedQueueTheSameBlocks) {
  const StereoCamera camera = vgaCamera();
  const sim::AnalyticScene scene = planeAndSphere();
  const StereoFrame frame = renderFrame(
      scene, camera, sim::lookAt({0.2, -0.3, -0.5}, {0, 0, 2.0}, -Eigen::Vector3d::UnitY()));
  // Φ of 16 voxels makes the boxes of levels 1 and 2 (2 m on) 9 or more blocks wide, past
  // the histogram's 8-cell box rows; one pixel in 16 keeps the naive search short there.
  StereoFrame sparse_frame = frame;
  sparse_frame.disparity_px = frame.disparity_px.clone();
  for (int v = 0; v < sparse_frame.disparity_px.rows; ++v)
    for (int u = 0; u < sparse_frame.disparity_px.cols; ++u)
      if (u % 4 != 0 || v % 4 != 0) sparse_frame.disparity_px.at<float>(v, u) = 0.0f;
  for (const auto& [histogram, truncation_vox] :
       {std::pair{0, 4.0}, std::pair{4, 4.0}, std::pair{0, 16.0}}) {
    const StereoFrame& frame_used = truncation_vox > 4.0 ? sparse_frame : frame;
    MapperConfig config;
    config.histogram_min_points = histogram;
    config.truncation_vox = truncation_vox;
    BlockOctree naive_tree(config.blockSizeM()), accel_tree(config.blockSizeM());
    const auto [naive, accel] =
        runNaiveAndAccelerated(config, frame_used, &naive_tree, &accel_tree);

    EXPECT_GT(naive.queue.size(), 100u);
    EXPECT_EQ(keysOf(naive.queue), keysOf(accel.queue))
        << "histogram " << histogram << ", Φ " << truncation_vox;
    EXPECT_EQ(naive.stats.valid_points, accel.stats.valid_points);
    EXPECT_EQ(naive_tree.blockCount(), accel_tree.blockCount());
    EXPECT_EQ(accel.stats.blocks_allocated, accel_tree.blockCount());
    // Algorithm 2 searches once per distinct block of the frame: far fewer searches.
    EXPECT_LT(accel.stats.octree_searches * 20, naive.stats.octree_searches)
        << "naive " << naive.stats.octree_searches << " accelerated "
        << accel.stats.octree_searches;
    // The counts are the octree's own: the lookup made exactly the searches it reports.
    EXPECT_EQ(accel_tree.searchCount(), accel.stats.octree_searches);
    EXPECT_EQ(naive_tree.searchCount(), naive.stats.octree_searches);
    std::printf(
        "[ lookup ] 640x480, histogram %d: %llu valid points, %zu blocks, searches naive %llu,"
        " accelerated %llu (%.0fx fewer)\n",
        histogram, static_cast<unsigned long long>(naive.stats.valid_points), naive.queue.size(),
        static_cast<unsigned long long>(naive.stats.octree_searches),
        static_cast<unsigned long long>(accel.stats.octree_searches),
        double(naive.stats.octree_searches) / accel.stats.octree_searches);
  }
}

namespace {

/// 32×32 image, principal point far left/up so every point lies in one block:
/// voxel 5 cm → block 0.4 m; Φ = 1 voxel = 0.05 m; disparity 50 → z = 500·0.1/50 = 1.0 m.
/// X = (u + 300)·1/500 ∈ [0.600, 0.662] ± 0.05 → block 1; Z ∈ [0.95, 1.05] → block 2.
struct OneBlockCase {
  StereoFrame frame =
      constantDepthFrame(*StereoCamera::create(32, 32, 500, 500, -300, -300, 0.1), 50.0f);
  MapperConfig config = [] {
    MapperConfig c;
    c.voxel_size_m = 0.05;
    c.truncation_vox = 1.0;
    c.weight_falloff_start_vox = 0.5;
    c.histogram_min_points = 0;
    c.lookup_region_px = 16;
    return c;
  }();
};

}  // namespace

TEST(BlockLookup, SearchCountsHandWorked) {
  OneBlockCase one_block;
  const StereoFrame& frame = one_block.frame;
  MapperConfig& config = one_block.config;

  config.lookup_mode = LookupMode::kNaive;
  BlockOctree naive_tree(config.blockSizeM());
  const LookupRun naive = runLookup(config, frame, &naive_tree);
  EXPECT_EQ(naive.stats.valid_points, 1024u);
  EXPECT_EQ(naive.stats.octree_searches, 1024u);  // one per pixel
  EXPECT_EQ(naive.stats.box_blocks, 1024u);       // one 1-block box per pixel
  ASSERT_EQ(naive.queue.size(), 1u);
  EXPECT_EQ(naive.queue[0]->key, (BlockKey{1, 1, 2}));

  config.lookup_mode = LookupMode::kAccelerated;
  BlockOctree accel_tree(config.blockSizeM());
  const LookupRun accel = runLookup(config, frame, &accel_tree);
  // Each of the four 16×16 regions finds the same one block; the frame searches it once.
  EXPECT_EQ(accel.stats.octree_searches, 1u);
  ASSERT_EQ(accel.queue.size(), 1u);
  EXPECT_EQ(accel.stats.blocks_queued, 1u);
  EXPECT_EQ(accel.stats.blocks_allocated, 1u);
  EXPECT_EQ(accel.stats.box_blocks, 4u);  // one distinct 1-block box per region
}

TEST(BlockLookup, WidelySpreadBoxesOffTheDenseGridCountLikeTheNaiveLookup) {
  // A 16×12 frame at f = 5 px seeing a plane 7.9 m away, measured in columns 0–7 of rows 0 and
  // 11 (one 16-px region): each pixel's box is ±0.75/5·7.9 m ≈ ±7.5 blocks wide and neighbouring
  // pixels' rays lie 1.6 m (10 blocks) apart, so neighbours' boxes overlap and the region's span
  // ~95 × 125 blocks × their depth, past the dense grid's 16 384 cells: they are counted
  // sparsely, sorted and summed (a search per block made that quadratic: the fuzzer's slow
  // unit). With the filter at ⌈24·16/192⌉ = 2 points only the overlaps pass: the sums decide.
  const StereoCamera camera = *StereoCamera::create(16, 12, 5, 5, 7.5, 5.5, 0.25);
  StereoFrame frame = constantDepthFrame(camera, 0.0f);
  for (int v : {0, 11})
    for (int u = 0; u < 8; ++u) frame.disparity_px.at<float>(v, u) = 5.0f * 0.25f / 7.9f;
  for (int histogram : {0, 24}) {
    MapperConfig config;
    config.histogram_min_points = histogram;
    BlockOctree naive_tree(config.blockSizeM()), accel_tree(config.blockSizeM());
    const auto [naive, accel] = runNaiveAndAccelerated(config, frame, &naive_tree, &accel_tree);
    EXPECT_EQ(accel.stats.valid_points, 16u);
    EXPECT_GT(accel.queue.size(), 100u);
    EXPECT_EQ(keysOf(naive.queue), keysOf(accel.queue)) << "histogram " << histogram;
    EXPECT_EQ(naive.stats.blocks_filtered, accel.stats.blocks_filtered)
        << "histogram " << histogram;
  }
}

TEST(BlockLookup, WorkBoundStopsTheFrameBeforeAnyBlockIsVisited) {
  // OneBlockCase: its boxes span 4 blocks (one per region, accelerated) or 1 024 (naive).
  OneBlockCase one_block;
  const StereoFrame& frame = one_block.frame;
  MapperConfig& config = one_block.config;
  for (const auto& [mode, work] :
       {std::pair{LookupMode::kAccelerated, 4}, {LookupMode::kNaive, 1024}}) {
    config.lookup_mode = mode;
    config.max_lookup_blocks_per_frame = work - 1;
    BlockOctree over_tree(config.blockSizeM());
    const LookupRun over = runLookup(config, frame, &over_tree);
    EXPECT_TRUE(over.stats.over_work_bound);
    EXPECT_EQ(over.stats.box_blocks, static_cast<uint64_t>(work));
    EXPECT_EQ(over.stats.valid_points, 1024u);
    EXPECT_EQ(over.stats.octree_searches, 0u);
    EXPECT_TRUE(over.queue.empty());
    EXPECT_EQ(over_tree.blockCount(), 0u);  // the allocating lookup allocated nothing

    config.max_lookup_blocks_per_frame = work;  // at the bound: looked up
    BlockOctree at_tree(config.blockSizeM());
    const LookupRun at = runLookup(config, frame, &at_tree);
    EXPECT_FALSE(at.stats.over_work_bound);
    ASSERT_EQ(at.queue.size(), 1u);
    EXPECT_EQ(at.queue[0]->key, (BlockKey{1, 1, 2}));
  }
}

TEST(BlockLookup, QueuesTheWholeTruncationBand) {
  // One valid pixel on the optical axis at z = 1.0 m, 2 cm voxels (16 cm blocks):
  // block z-range 6 = [0.96, 1.12). Φ = 4 voxels = 8 cm → band [0.92, 1.08] → blocks 5 and 6.
  // x, y = 0 exactly on a block corner: band ±8 cm → blocks −1 and 0 on both axes.
  const StereoCamera camera = *StereoCamera::create(5, 5, 500, 500, 2, 2, 0.1);
  StereoFrame frame = constantDepthFrame(camera, 0.0f);
  frame.disparity_px.at<float>(2, 2) = 50.0f;  // z = 1.0
  MapperConfig config;
  config.histogram_min_points = 0;
  BlockOctree tree(config.blockSizeM());
  const LookupRun run = runLookup(config, frame, &tree);
  EXPECT_EQ(run.stats.valid_points, 1u);
  EXPECT_EQ(run.stats.box_blocks, 8u);  // 2 × 2 × 2 blocks
  std::set<std::tuple<int, int, int>> expected;
  for (int z : {5, 6})
    for (int y : {-1, 0})
      for (int x : {-1, 0}) expected.insert({x, y, z});
  const auto got = keysOf(run.queue);
  const std::set<std::tuple<int, int, int>> got_set(got.begin(), got.end());
  EXPECT_EQ(got_set, expected);
  EXPECT_EQ(got.size(), expected.size());  // each block queued once
}

TEST(BlockLookup, BandGrowsWithTheMeasurementLevel) {
  // Same pixel at z = 2.5 m (level 1, s = 2): Φ = 4·2·2 cm = 16 cm along the ray (the optical
  // axis: the pixel is the principal point) → z ∈ [2.34, 2.66] → blocks 14 ([2.24, 2.40)), 15,
  // 16 ([2.56, 2.72)). Laterally only the voxels that project onto the pixel: 0.75 px at the
  // far end, 0.75 · 2.66 / 500 = 4.0 mm → x, y ∈ [−0.004, 0.004] → blocks −1 and 0.
  const StereoCamera camera = *StereoCamera::create(5, 5, 500, 500, 2, 2, 0.1);
  StereoFrame frame = constantDepthFrame(camera, 0.0f);
  frame.disparity_px.at<float>(2, 2) = 20.0f;  // z = 50/20 = 2.5
  MapperConfig config;
  config.level_mode = LevelMode::kDepth;  // the depths above straddle the thesis' 2 m and 4 m
  config.histogram_min_points = 0;
  BlockOctree tree(config.blockSizeM());
  const LookupRun run = runLookup(config, frame, &tree);
  std::set<int> zs;
  for (const VoxelBlock* b : run.queue) zs.insert(b->key.z);
  EXPECT_EQ(zs, (std::set<int>{14, 15, 16}));
  std::set<int> xs;
  for (const VoxelBlock* b : run.queue) xs.insert(b->key.x);
  EXPECT_EQ(xs, (std::set<int>{-1, 0}));
  EXPECT_EQ(run.queue.size(), 2u * 2u * 3u);
}

// The ray band must reach every block in which fusion puts a voxel within the band of its
// measurement: fuse the frame into every block of a box around the queue (a superset of
// anything a band could reach); each voxel that then holds a distance within Φ of its
// measurement's level (the surface depth recovered from the voxel's own distance, eq. 3.15)
// must lie in a queued block. (Voxels farther in front are fused, clamped to −Φ, only where a
// band brings their block.) At near range (level 0) and far range (levels 1 and 2, whose Φ
// spans several blocks), from an oblique pose, with noise.
namespace {
void expectEveryBlockFusionCanUpdateIsQueued(const Eigen::Vector3d& world_offset_m) {
  MapperConfig config;
  config.histogram_min_points = 0;  // the filter drops sparse blocks on purpose
  config.voxel_size_m = 0.01;
  config.level_mode =
      LevelMode::kDepth;  // the scene's depths (1.2, 3, 6 m) put points at all three levels
  const StereoCamera camera = *StereoCamera::create(160, 120, 131.25, 131.25, 79.5, 59.5, 0.1);
  const Eigen::Vector3d& o = world_offset_m;
  sim::AnalyticScene scene;
  scene.add(sim::makePlane(o + Eigen::Vector3d(0, 0, 6.0), {0.3, -0.2, -1.0}));
  scene.add(sim::makeSphere(o + Eigen::Vector3d(0.4, 0.1, 1.2), 0.3));
  scene.add(sim::makeSphere(o + Eigen::Vector3d(-1.0, -0.3, 3.0), 0.5));
  const Eigen::Isometry3d pose =
      sim::lookAt(o + Eigen::Vector3d(0.2, -0.1, -0.3), o + Eigen::Vector3d(0.1, 0.0, 3.0),
                  -Eigen::Vector3d::UnitY());
  const StereoFrame frame = renderFrame(scene, camera, pose, 0.3, 7);
  ThreadPool pool(2);
  BlockOctree tree(config.blockSizeM());
  const LookupRun run = runLookup(config, frame, &tree);
  ASSERT_GT(run.queue.size(), 200u);
  std::set<BlockKey> queued;
  BlockKey lo = run.queue.front()->key, hi = lo;
  for (const VoxelBlock* b : run.queue) {
    queued.insert(b->key);
    lo = componentMin(lo, b->key);
    hi = componentMax(hi, b->key);
  }
  BlockOctree all(config.blockSizeM());
  const LevelThresholds thresholds =
      levelThresholdsFor(stageConfigs(config).pipeline.measurement.levels,
                         frame.camera.fx() * frame.camera.baseline());
  std::vector<VoxelBlock*> every;
  for (int32_t z = lo.z - 2; z <= hi.z + 2; ++z)
    for (int32_t y = lo.y - 2; y <= hi.y + 2; ++y)
      for (int32_t x = lo.x - 2; x <= hi.x + 2; ++x) every.push_back(all.findOrAllocate({x, y, z}));
  SurfaceFuser fuser(stageConfigs(config).pipeline.fusion, &pool);
  std::vector<VoxelBlock*> updated;
  MeasurementImage measurements;
  measurements.build(frame, stageConfigs(config).pipeline.measurement, &pool);
  const FusionStats stats = fuser.fuse(frame, measurements, all, every, &updated);
  ASSERT_GT(stats.blocks_updated, 100u);
  const TruncationBand band = config.truncationBand();
  const Eigen::Isometry3d T_camera_world = frame.T_world_camera.inverse();
  size_t in_band[kNumLevels] = {}, missed = 0;
  for (const VoxelBlock* b : updated)
    for (int level = 0; level < kNumLevels; ++level) {
      const int side = levelSide(level);
      for (int k = 0; k < side; ++k)
        for (int j = 0; j < side; ++j)
          for (int i = 0; i < side; ++i) {
            const Voxel& v = b->at(level, i, j, k);
            if (!(v.weight > 0.0f)) continue;
            const Eigen::Vector3d x_c = T_camera_world * voxelCentre(all, b->key, level, i, j, k);
            const double surface_depth_m =
                x_c.z() * (1.0 - v.sdf_m / x_c.norm());  // eq. 3.15 solved for z
            const double phi_m = band.measurementM(levelForDepth(surface_depth_m, thresholds));
            if (std::abs(v.sdf_m) > 0.999 * phi_m) continue;
            ++in_band[level];
            if (!queued.count(b->key)) {
              ++missed;
              ADD_FAILURE() << "block " << b->key << " level " << level << " sdf " << v.sdf_m
                            << " not queued";
            }
          }
    }
  EXPECT_EQ(missed, 0u);
  for (int level = 0; level < kNumLevels; ++level)
    EXPECT_GT(in_band[level], 100u) << "level " << level;
}
}  // namespace

TEST(BlockLookup, EveryBlockFusionCanUpdateIsQueued) {
  expectEveryBlockFusionCanUpdateIsQueued(Eigen::Vector3d::Zero());
}

// The same 12 km from the world origin, where a float world coordinate is off by a millimetre:
// the lookup's boxes are relative to the camera's block, so the margin still holds.
TEST(BlockLookup, EveryBlockFusionCanUpdateIsQueuedFarFromTheOrigin) {
  expectEveryBlockFusionCanUpdateIsQueued(Eigen::Vector3d(12345.6, -7890.1, 2345.7));
}

// Moving the camera by whole blocks moves every queued key by exactly as many blocks, however
// far from the origin: nothing in the per-pixel arithmetic depends on the camera's position.
TEST(BlockLookup, CameraMovedByWholeBlocksShiftsTheQueueExactly) {
  MapperConfig config;
  config.histogram_min_points = 0;
  config.voxel_size_m = 0.02;
  const StereoFrame near_frame =
      renderFrame(planeAndSphere(), vgaCamera(),
                  sim::lookAt({0.21, -0.13, -0.4}, {0, 0, 2.0}, -Eigen::Vector3d::UnitY()));
  BlockOctree near_tree(config.blockSizeM());
  const LookupRun near_run = runLookup(config, near_frame, &near_tree);
  ASSERT_GT(near_run.queue.size(), 500u);
  const BlockKey shift{1000003, -2000017, 300007};  // ≈ 160 km at 8 cm blocks
  StereoFrame far_frame = near_frame;
  far_frame.T_world_camera.translation() +=
      config.blockSizeM() * Eigen::Vector3d(shift.x, shift.y, shift.z);
  BlockOctree far_tree(config.blockSizeM());
  const LookupRun far_run = runLookup(config, far_frame, &far_tree);
  ASSERT_EQ(far_run.queue.size(), near_run.queue.size());
  for (size_t i = 0; i < near_run.queue.size(); ++i) {
    const BlockKey& k = near_run.queue[i]->key;
    ASSERT_EQ(far_run.queue[i]->key, (BlockKey{k.x + shift.x, k.y + shift.y, k.z + shift.z}))
        << "block " << i;
  }
}

TEST(BlockLookup, InvalidDisparitiesAreSkipped) {
  const StereoCamera camera = *StereoCamera::create(8, 1, 500, 500, 4, 0, 0.1);
  StereoFrame frame = constantDepthFrame(camera, 0.0f);
  float* row = frame.disparity_px.ptr<float>(0);
  row[0] = NAN;
  row[1] = INFINITY;
  row[2] = -INFINITY;
  row[3] = -5.0f;
  row[4] = 0.0f;
  row[5] = 2.0f;    // z = 25 m: beyond max_depth_m = 8
  row[6] = 1000.f;  // z = 5 cm: nearer than min_depth_m = 0.1
  row[7] = 25.0f;   // z = 2 m: the only valid one
  MapperConfig config;
  config.histogram_min_points = 0;
  for (LookupMode mode : {LookupMode::kNaive, LookupMode::kAccelerated}) {
    config.lookup_mode = mode;
    BlockOctree tree(config.blockSizeM());
    const LookupRun run = runLookup(config, frame, &tree);
    EXPECT_EQ(run.stats.valid_points, 1u);
    EXPECT_FALSE(run.queue.empty());
  }
}

TEST(BlockLookup, HistogramFilterDropsSparseBlocks) {
  // Region of 16×16: 253 pixels on a plane at 1 m, 3 isolated pixels far away at 5 m.
  const StereoCamera camera = *StereoCamera::create(16, 16, 500, 500, 8, 8, 0.1);
  StereoFrame frame = constantDepthFrame(camera, 50.0f);  // z = 1 m
  frame.disparity_px.at<float>(0, 0) = 10.0f;             // z = 5 m
  frame.disparity_px.at<float>(0, 1) = 10.0f;
  frame.disparity_px.at<float>(1, 0) = 10.0f;
  MapperConfig config;
  auto farBlocks = [](const std::vector<VoxelBlock*>& queue) {
    int n = 0;
    for (const VoxelBlock* b : queue) n += b->key.z >= 20;  // 5 m / 0.16 = 31
    return n;
  };
  config.histogram_min_points = 0;
  BlockOctree all_tree(config.blockSizeM());
  const LookupRun all = runLookup(config, frame, &all_tree);
  EXPECT_GT(farBlocks(all.queue), 0);

  config.histogram_min_points = 4;
  BlockOctree filtered_tree(config.blockSizeM());
  const LookupRun filtered = runLookup(config, frame, &filtered_tree);
  EXPECT_EQ(farBlocks(filtered.queue), 0);
  EXPECT_GT(filtered.stats.blocks_filtered, 0u);
  EXPECT_EQ(filtered.queue.size() + farBlocks(all.queue), all.queue.size());
  // Filtered blocks are never allocated.
  EXPECT_EQ(filtered_tree.blockCount(), filtered.queue.size());
}

TEST(BlockLookup, ResultDoesNotDependOnThreadsOrRegionSize) {
  const StereoCamera camera = vgaCamera();
  const StereoFrame frame =
      renderFrame(planeAndSphere(), camera,
                  sim::lookAt({-0.4, 0.2, -0.2}, {0.1, 0, 2.0}, -Eigen::Vector3d::UnitY()));
  MapperConfig config;
  config.histogram_min_points = 0;
  std::vector<std::tuple<int, int, int>> reference;
  for (int threads : {1, 2, 4})
    for (int region : {8, 16, 37}) {
      config.num_threads = threads;
      config.lookup_region_px = region;
      BlockOctree tree(config.blockSizeM());
      const auto keys = keysOf(runLookup(config, frame, &tree).queue);
      if (reference.empty()) reference = keys;
      EXPECT_EQ(keys, reference) << threads << " threads, region " << region;
    }
}

TEST(BlockLookup, VectorPathEqualsScalarPathOnHostileFrames) {
  // The AVX2 path must produce exactly the scalar path's boxes: same queue, same counts, same
  // histogram decisions, on frames mixing valid disparities with 0, negative, NaN, ±inf,
  // depths outside [min, max], all three levels, widths that are not multiples of 4, and a
  // camera so far out that some bands leave the key range.
  if (!lookupUsesSimd()) GTEST_SKIP() << "CPU without AVX2: only the scalar path exists";
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> disparity(0.5f, 80.0f);
  std::uniform_int_distribution<int> special(0, 19);
  const float specials[] = {0.0f, -3.0f, std::nanf(""), HUGE_VALF, -HUGE_VALF, 1e-30f, 1e30f};
  for (int trial = 0; trial < 12; ++trial) {
    const int width = 61 + trial, height = 37 + 2 * trial;
    const StereoCamera camera =
        *StereoCamera::create(width, height, 60.0, 62.0, width * 0.45, height * 0.55, 0.12);
    StereoFrame frame = constantDepthFrame(camera, 0.0f);
    for (int v = 0; v < height; ++v)
      for (int u = 0; u < width; ++u) {
        const int pick = special(rng);
        frame.disparity_px.at<float>(v, u) = pick < 7 ? specials[pick] : disparity(rng);
      }
    Eigen::Vector3d axis = Eigen::Vector3d::Random().normalized();
    frame.T_world_camera = Eigen::AngleAxisd(0.3 * trial, axis);
    frame.T_world_camera.translation() = Eigen::Vector3d::Random() * 3.0;
    // The last trial (1 cm voxels, 8 cm blocks) sits 2 m inside the key range's edge.
    if (trial == 11) frame.T_world_camera.translation().x() = BlockOctree::kMaxKey * 0.08 - 2.0;
    for (int histogram : {0, 3}) {
      MapperConfig config;
      config.voxel_size_m = trial % 2 ? 0.01 : 0.04;
      config.histogram_min_points = histogram;
      config.lookup_region_px = 8 + trial;
      ThreadPool pool(2);
      const ScalarAndVector r = runScalarAndVector(config, frame, &pool);
      const LookupStats& s = r.scalar;
      const LookupStats& v = r.vector;
      EXPECT_GT(s.valid_points, 0u);
      EXPECT_EQ(r.scalar_keys, r.vector_keys) << "trial " << trial;
      EXPECT_EQ(s.valid_points, v.valid_points);
      EXPECT_EQ(s.octree_searches, v.octree_searches);
      EXPECT_EQ(s.blocks_allocated, v.blocks_allocated);
      EXPECT_EQ(s.blocks_filtered, v.blocks_filtered);
    }
  }
}

TEST(BlockLookup, VectorPathEqualsScalarPathOnSmoothFrames) {
  // Smooth surfaces give long runs of pixels sharing one band box, which the AVX2 path counts
  // a group of four at a time; runs broken by invalid pixels, box changes at any lane and
  // boxes alternating between neighbours must still give the scalar path's per-box counts.
  // Many histogram thresholds make a count that is off by one change which blocks pass.
  if (!lookupUsesSimd()) GTEST_SKIP() << "CPU without AVX2: only the scalar path exists";
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> special(0, 99);
  std::normal_distribution<float> noise(0.0f, 0.02f);
  const float specials[] = {0.0f, -3.0f, std::nanf(""), HUGE_VALF, 1e-30f, 1e30f};
  for (int trial = 0; trial < 8; ++trial) {
    const int width = 90 + 3 * trial, height = 50 + trial;
    const StereoCamera camera =
        *StereoCamera::create(width, height, 70.0, 70.0, width * 0.5, height * 0.5, 0.12);
    StereoFrame frame = constantDepthFrame(camera, 0.0f);
    // A tilted plane (disparity linear in u and v) spanning all three levels; odd trials add
    // noise so that pixels near a box edge alternate between two boxes.
    const float d0 = 2.0f + 3.0f * trial, du = 0.05f * (trial % 3 - 1), dv = 0.08f;
    const int special_per_100 = trial < 4 ? 3 : 30;
    for (int v = 0; v < height; ++v)
      for (int u = 0; u < width; ++u) {
        float d = d0 + du * u + dv * v + (trial % 2 ? noise(rng) : 0.0f);
        const int pick = special(rng);
        if (pick < special_per_100) d = specials[pick % 6];
        frame.disparity_px.at<float>(v, u) = d;
      }
    frame.T_world_camera =
        Eigen::AngleAxisd(0.2 * trial, Eigen::Vector3d(0.3, -1.0, 0.5).normalized());
    frame.T_world_camera.translation() = Eigen::Vector3d(0.1 * trial, -0.7, 0.4);
    for (int histogram : {0, 2, 3, 5, 9, 16, 33, 64}) {
      MapperConfig config;
      config.voxel_size_m = trial % 3 == 0 ? 0.04 : (trial % 3 == 1 ? 0.02 : 0.01);
      config.histogram_min_points = histogram;
      config.lookup_region_px = 13 + 5 * trial;
      // Φ of 4 voxels is half an 8-voxel block, so lo and hi of a box change together; with
      // 3 voxels a box can change in its hi corner alone.
      config.truncation_vox = trial % 2 ? 3.0 : 4.0;
      ThreadPool pool(2);
      const ScalarAndVector r = runScalarAndVector(config, frame, &pool);
      const LookupStats& s = r.scalar;
      const LookupStats& v = r.vector;
      EXPECT_GT(s.valid_points, 0u);
      EXPECT_EQ(r.scalar_keys, r.vector_keys) << "trial " << trial << ", histogram " << histogram;
      EXPECT_EQ(s.valid_points, v.valid_points);
      EXPECT_EQ(s.blocks_filtered, v.blocks_filtered)
          << "trial " << trial << ", histogram " << histogram;
    }
  }
}

TEST(BlockLookup, VectorPathEqualsScalarPathWhenEveryBoxIsTheOriginBlock) {
  // The AVX2 path compares each group's first lane with the region's previous box; before a
  // region has one, a box of all-zero keys must not pass for a repeat of it. A narrow camera
  // 1 m in front of block (0, 0, 0) with Φ far below a block puts every box there.
  if (!lookupUsesSimd()) GTEST_SKIP() << "CPU without AVX2: only the scalar path exists";
  MapperConfig config;
  ThreadPool pool(1);
  config.voxel_size_m = 0.01;  // 8 cm blocks
  config.truncation_vox = 0.5;
  config.weight_falloff_start_vox = 0.25;
  config.histogram_min_points = 0;
  const StereoCamera camera = *StereoCamera::create(64, 48, 2000.0, 2000.0, 32.0, 24.0, 0.12);
  StereoFrame frame = constantDepthFrame(camera, static_cast<float>(2000.0 * 0.12 / 1.0));
  frame.T_world_camera.translation() = Eigen::Vector3d(0.04, 0.04, 0.04 - 1.0);
  const ScalarAndVector r = runScalarAndVector(config, frame, &pool);
  EXPECT_EQ(r.scalar.valid_points, 64u * 48u);
  EXPECT_EQ(r.scalar_keys, (std::vector<std::tuple<int, int, int>>{{0, 0, 0}}));
  EXPECT_EQ(r.scalar_keys, r.vector_keys);
  EXPECT_EQ(r.scalar.valid_points, r.vector.valid_points);
}

TEST(BlockLookup, VectorPathEqualsScalarPathWhereTheSumOrderDecidesTheBlock) {
  // Each world coordinate is a sum of three products and the translation; double addition
  // is not associative, so both paths must add in the same order or a point within an ulp of
  // a block face lands in different blocks. Builds such a point: a rotation for which
  // ((a0 + a1) + a2) and (a0 + (a1 + a2)) differ in z, and a translation putting the lower
  // band face exactly on a block face for one order only.
  if (!lookupUsesSimd()) GTEST_SKIP() << "CPU without AVX2: only the scalar path exists";
  MapperConfig config;
  ThreadPool pool(1);
  config.voxel_size_m = 0.125;  // 1 m blocks: the key is the floor of the world coordinate
  config.truncation_vox = 4.0;  // Φ = 0.5 m at level 0
  config.histogram_min_points = 0;
  const StereoCamera camera = *StereoCamera::create(8, 4, 100.0, 100.0, 3.7, 2.1, 0.1);
  const int u = 2, v = 1;
  const float disparity = 20.0f;  // z = 0.5 m: level 0
  const double z = camera.fx() * camera.baseline() / disparity;
  const double p[3] = {(u - camera.cx()) * z * (1.0 / camera.fx()),
                       (v - camera.cy()) * z * (1.0 / camera.fy()), z};
  const double band = 0.5;
  std::mt19937 rng(3);
  bool found = false;
  for (int attempt = 0; attempt < 10000 && !found; ++attempt) {
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(std::uniform_real_distribution<double>(0.0, 6.0)(rng),
                          Eigen::Vector3d::Random().normalized())
            .toRotationMatrix();
    const double a0 = R(2, 0) * p[0], a1 = R(2, 1) * p[1], a2 = R(2, 2) * p[2];
    const double left = (a0 + a1) + a2, right = a0 + (a1 + a2);
    if (left == right) continue;
    for (int face = -3; face <= 3 && !found; ++face) {
      const double t_z = (face + band) - left;
      if (std::floor((left + t_z) - band) == std::floor((right + t_z) - band)) continue;
      found = true;
      StereoFrame frame = constantDepthFrame(camera, 0.0f);
      frame.disparity_px.at<float>(v, u) = disparity;
      frame.T_world_camera.linear() = R;
      frame.T_world_camera.translation() = Eigen::Vector3d(0.3, -0.2, t_z);
      const ScalarAndVector r = runScalarAndVector(config, frame, &pool);
      EXPECT_EQ(r.scalar.valid_points, 1u);
      EXPECT_EQ(r.vector.valid_points, 1u);
      EXPECT_EQ(r.scalar_keys, r.vector_keys) << "attempt " << attempt;
    }
  }
  EXPECT_TRUE(found) << "no point found whose block depends on the order of the sum";
}

TEST(BlockLookup, NaiveAndAcceleratedAgreeWhenTheFrameSpansTooManyBlocksForTheBitmap) {
  // The accelerated lookup de-duplicates the frame's blocks on a bitmap over their box, or,
  // when that box is too large, in a hash set followed by a sort. 2 mm voxels (1.6 cm
  // blocks) and depths of 0.3 m (left half, every 8th pixel) and 7 m (right half, every 64th:
  // a few points spread wide keep the far blocks, 7 KB each, few) make the box about
  // 280 × 400 × 420 blocks, past the bitmap's cap.
  const StereoCamera camera = vgaCamera();
  StereoFrame frame = constantDepthFrame(camera, 0.0f);
  const double fb = camera.fx() * camera.baseline();
  for (int v = 0; v < frame.disparity_px.rows; v += 8)
    for (int u = 0; u < frame.disparity_px.cols; u += 8) {
      const bool near = u < camera.width() / 2;
      if (near || (u % 64 == 0 && v % 64 == 0))
        frame.disparity_px.at<float>(v, u) = static_cast<float>(fb / (near ? 0.3 : 7.0));
    }
  // No histogram filter: 8 px apart at 7 m, the far points share no block, and the filter
  // would drop them all (it is tested above; here only the de-duplication matters).
  {
    MapperConfig config;
    config.voxel_size_m = 0.002;
    config.histogram_min_points = 0;
    BlockOctree naive_tree(config.blockSizeM()), accel_tree(config.blockSizeM());
    const auto [naive, accel] = runNaiveAndAccelerated(config, frame, &naive_tree, &accel_tree);

    ASSERT_GT(naive.queue.size(), 100u);
    EXPECT_EQ(keysOf(naive.queue), keysOf(accel.queue));
    EXPECT_EQ(accel.stats.blocks_allocated, accel_tree.blockCount());
    // The queued blocks alone span a box too large for the bitmap: the fallback ran.
    BlockKey lo = naive.queue.front()->key, hi = lo;
    for (const VoxelBlock* b : naive.queue) {
      lo = componentMin(lo, b->key);
      hi = componentMax(hi, b->key);
    }
    BlockKeyBitmap bitmap;
    EXPECT_FALSE(bitmap.reset(lo, hi)) << "box " << lo << " – " << hi;
  }
}

TEST(BlockLookup, HistogramFilterKeepsAFarSparseTrueSurface) {
  // A wall at 7.5 m (the 2³ level, 16 cm blocks), matched on one pixel in 16 (every 4th row and
  // column: weak texture). A 16×16 region sees 16 of its points, spread over the 2 × 2 blocks
  // its footprint (23 cm) straddles: about 4 points per block and region, the filter's
  // threshold. The filter is for isolated outliers, not for a sparse surface: every block the
  // unfiltered bands reach must stay queued.
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 7.5}, {0, 0, -1}));
  StereoFrame frame = renderFrame(scene, vgaCamera(), Eigen::Isometry3d::Identity());
  for (int v = 0; v < frame.disparity_px.rows; ++v)
    for (int u = 0; u < frame.disparity_px.cols; ++u)
      if (v % 4 != 0 || u % 4 != 0) frame.disparity_px.at<float>(v, u) = 0.0f;
  MapperConfig config;  // histogram_min_points 4
  ASSERT_EQ(config.histogram_min_points, 4);
  BlockOctree filtered_tree(config.blockSizeM());
  const LookupRun filtered = runLookup(config, frame, &filtered_tree);
  config.histogram_min_points = 0;
  BlockOctree all_tree(config.blockSizeM());
  const LookupRun all = runLookup(config, frame, &all_tree);
  EXPECT_EQ(keysOf(filtered.queue), keysOf(all.queue))
      << filtered.stats.blocks_filtered << " (region, block) pairs dropped";
}
