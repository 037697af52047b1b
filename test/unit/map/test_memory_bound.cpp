// The memory bound: block erase in the octree, the eviction policy, and the Mapper keeping its
// budget with a mesh that stays equal to a rebuild and to what a subscriber reconstructs.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "MeshTestSupport.h"
#include "stereo_fusion/map/EvictionPolicy.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

/// An endless corridor: floor 0.5 m below the camera, a wall 2 m in front. A camera sliding
/// along +x keeps seeing new space, so an unbounded map keeps growing.
sim::AnalyticScene corridor() {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0.5, 0}, {0, -1, 0}), {180, 160, 120});
  scene.add(sim::makePlane({0, 0, 2.0}, {0, 0, -1}), {90, 120, 200});
  return scene;
}

StereoFrame corridorFrame(const sim::AnalyticScene& scene, double x_m) {
  Eigen::Isometry3d T_world_camera =
      Eigen::Isometry3d::Identity();  // optical frame: looking along +z
  T_world_camera.translation() = Eigen::Vector3d(x_m, 0, 0);
  return renderFrame(scene, qvgaCamera(), T_world_camera);
}

MapperConfig boundedConfig() {
  MapperConfig config;
  config.voxel_size_m = 0.04;
  config.num_threads = 2;
  config.level_mode = LevelMode::kDepth;  // the budgets below were sized with the thesis' levels
  return config;
}

}  // namespace

TEST(BlockOctreeErase, RemovesBlocksAndPrunesEmptyNodes) {
  BlockOctree map(0.16);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> coord(-40, 40);
  std::set<BlockKey> keys;
  while (keys.size() < 600) keys.insert({coord(rng), coord(rng), coord(rng)});
  for (const BlockKey& k : keys) ASSERT_NE(map.findOrAllocate(k), nullptr);
  const size_t nodes_full = map.nodeCount();
  const size_t bytes_full = map.memoryBytes();

  std::vector<BlockKey> half, rest;
  for (const BlockKey& k : keys) (half.size() < 300 ? half : rest).push_back(k);
  half.push_back({1000, 1000, 1000});  // missing keys are ignored
  EXPECT_EQ(map.erase(half), 300u);
  EXPECT_EQ(map.blockCount(), 300u);
  for (size_t i = 0; i < 300; ++i) EXPECT_EQ(map.find(half[i]), nullptr) << half[i];
  for (const BlockKey& k : rest) {
    const VoxelBlock* b = map.find(k);
    ASSERT_NE(b, nullptr) << k;
    EXPECT_EQ(b->key, k);
  }
  EXPECT_LT(map.nodeCount(), nodes_full);
  EXPECT_LT(map.memoryBytes(), bytes_full);
  // Sorted iteration sees exactly the kept blocks.
  std::vector<BlockKey> listed;
  for (const VoxelBlock* b : map.blocksSortedByKey()) listed.push_back(b->key);
  EXPECT_EQ(listed, rest);

  // Erasing everything leaves no node at all, and the tree grows again from scratch.
  EXPECT_EQ(map.erase(rest), 300u);
  EXPECT_EQ(map.blockCount(), 0u);
  EXPECT_EQ(map.nodeCount(), 0u);
  EXPECT_EQ(map.height(), 0);
  bool allocated = false;
  ASSERT_NE(map.findOrAllocate({3, -4, 5}, &allocated), nullptr);
  EXPECT_TRUE(allocated);
  EXPECT_EQ(map.blockCount(), 1u);
  EXPECT_NE(map.find({3, -4, 5}), nullptr);
}

TEST(BlockOctreeErase, EraseOneOfTwoSiblingsKeepsTheOther) {
  BlockOctree map(0.16);
  map.findOrAllocate({0, 0, 0});
  map.findOrAllocate({1, 0, 0});  // same height-1 node
  const size_t nodes = map.nodeCount();
  EXPECT_EQ(map.erase({{0, 0, 0}}), 1u);
  EXPECT_EQ(map.nodeCount(), nodes) << "the shared node still holds a block";
  EXPECT_NE(map.find({1, 0, 0}), nullptr);
  EXPECT_EQ(map.find({0, 0, 0}), nullptr);
}

TEST(EvictionPolicy, HandWorkedBudgetAndDistance) {
  BlockOctree map(1.0);  // 1 m blocks: block (x, 0, 0) has its centre at x + 0.5
  EvictionPolicy policy;
  // Blocks x = 0..4 last updated at frames 5, 3, 3, never, 9, as the change log reports them.
  for (int x = 0; x < 5; ++x) map.findOrAllocate({x, 0, 0});
  policy.recordUpdates(map, {{1, 0, 0}, {2, 0, 0}}, 3);
  policy.recordUpdates(map, {{0, 0, 0}}, 5);
  policy.recordUpdates(map, {{4, 0, 0}, {7, 7, 7}}, 9);  // (7, 7, 7): no block, skipped
  EXPECT_EQ(policy.lastUpdateFrame(*map.find({3, 0, 0})), 0u);
  EXPECT_EQ(policy.lastUpdateFrame(*map.find({2, 0, 0})), 3u);
  auto selectBlocksToEvict = [&](const BlockOctree& m, const Eigen::Vector3d& c,
                                 const EvictionLimits& l) { return policy.select(m, c, l); };
  const Eigen::Vector3d camera(0.5, 0.5, 0.5);  // at the centre of block 0
  // No limit, or a budget not exceeded: nothing.
  EXPECT_TRUE(selectBlocksToEvict(map, camera, {}).empty());
  EXPECT_TRUE(selectBlocksToEvict(map, camera, {5, 0.0}).empty());
  // Budget 3: evict 2. Oldest is x = 3 (never updated); then x = 1 and x = 2 tie at frame 3 and
  // the farther, x = 2 (2 m away against 1 m), goes.
  EXPECT_EQ(selectBlocksToEvict(map, camera, {3, 0.0}),
            (std::vector<BlockKey>{{2, 0, 0}, {3, 0, 0}}));
  // Distance 2.5 m: centres at 3 m and 4 m are beyond, whatever their age.
  EXPECT_EQ(selectBlocksToEvict(map, camera, {0, 2.5}),
            (std::vector<BlockKey>{{3, 0, 0}, {4, 0, 0}}));
  // Both: 3 and 4 by distance, then among 0, 1, 2 one more for a budget of 2: x = 2 (frame 3,
  // farther).
  EXPECT_EQ(selectBlocksToEvict(map, camera, {2, 2.5}),
            (std::vector<BlockKey>{{2, 0, 0}, {3, 0, 0}, {4, 0, 0}}));
}

TEST(MemoryBound, BudgetHoldsAfterEveryFrameAndEvictsTheLeastRecent) {
  const sim::AnalyticScene scene = corridor();
  MapperConfig config = boundedConfig();
  config.max_blocks = 250;
  Mapper mapper(config);
  uint64_t evicted_total = 0;
  for (int f = 0; f < 40; ++f) {
    std::map<BlockKey, uint64_t> before;
    for (const VoxelBlock* b : mapper.tsdf().blocks()) before[b->key] = mapper.lastUpdateFrame(*b);
    const IntegrationResult r = mapper.integrate(corridorFrame(scene, 0.15 * f));
    ASSERT_TRUE(r.accepted) << r.error;
    EXPECT_LE(mapper.tsdf().blockCount(), 250u) << "frame " << f;
    evicted_total += r.evicted_blocks.size();
    uint64_t oldest_kept = UINT64_MAX;
    for (const VoxelBlock* b : mapper.tsdf().blocks())
      oldest_kept = std::min(oldest_kept, mapper.lastUpdateFrame(*b));
    for (const BlockKey& k : r.evicted_blocks) {
      EXPECT_EQ(mapper.tsdf().find(k), nullptr) << k;
      EXPECT_FALSE(std::binary_search(r.updated_blocks.begin(), r.updated_blocks.end(), k)) << k;
      auto it = before.find(k);
      // A block that existed before the frame is only evicted if every kept block is at least as
      // recent.
      if (it != before.end()) {
        EXPECT_LE(it->second, oldest_kept) << "evicted " << k << " at frame " << f;
      }
    }
  }
  EXPECT_GT(evicted_total, 200u) << "the corridor must outgrow the budget";
  EXPECT_EQ(mapper.blocksEvicted(), evicted_total);
  // The kept map is the recent end of the corridor: every block last updated in the first
  // quarter of the run is gone.
  for (const VoxelBlock* b : mapper.tsdf().blocks())
    EXPECT_GT(mapper.lastUpdateFrame(*b), 10u) << b->key;
}

TEST(MemoryBound, DistanceLimitKeepsOnlyNearbyBlocks) {
  const sim::AnalyticScene scene = corridor();
  MapperConfig config = boundedConfig();
  config.max_distance_from_camera_m = 3.0;
  config.max_depth_m = 3.0;  // the bound may not be below the fusion range (validateMapperConfig)
  Mapper mapper(config);
  Mapper unbounded(boundedConfig());
  for (int f = 0; f < 30; ++f) {
    const StereoFrame frame = corridorFrame(scene, 0.2 * f);
    ASSERT_TRUE(mapper.integrate(frame).accepted);
    ASSERT_TRUE(unbounded.integrate(frame).accepted);
    const Eigen::Vector3d camera = frame.T_world_camera.translation();
    const Eigen::Vector3d half = Eigen::Vector3d::Constant(mapper.tsdf().blockSize() / 2);
    size_t near_in_unbounded = 0;
    for (const VoxelBlock* b : unbounded.tsdf().blocks())
      near_in_unbounded += (unbounded.tsdf().blockOrigin(b->key) + half - camera).norm() <= 3.0;
    for (const VoxelBlock* b : mapper.tsdf().blocks())
      ASSERT_LE((mapper.tsdf().blockOrigin(b->key) + half - camera).norm(), 3.0)
          << b->key << " frame " << f;
    // Nothing near was evicted: the near part of the unbounded map is all there.
    EXPECT_EQ(mapper.tsdf().blockCount(), near_in_unbounded) << "frame " << f;
  }
  EXPECT_GT(mapper.blocksEvicted(), 100u);
  EXPECT_LT(mapper.tsdf().blockCount(), unbounded.tsdf().blockCount() / 2);
}

TEST(MemoryBound, MeshAfterEvictionEqualsARebuildAndTheStreamedCopy) {
  const sim::AnalyticScene scene = corridor();
  MapperConfig config = boundedConfig();
  config.max_blocks = 300;
  Mapper mapper(config);
  // A subscriber's copy, kept only from the per-frame changes (what MeshUpdate carries).
  std::map<BlockKey, SubMesh> streamed;
  size_t removed_by_eviction = 0;
  for (int f = 0; f < 30; ++f) {
    const IntegrationResult r = mapper.integrate(corridorFrame(scene, 0.15 * f));
    ASSERT_TRUE(r.accepted);
    for (const BlockKey& k : r.mesh.changed) streamed[k] = mapper.mesh().submeshes().at(k);
    for (const BlockKey& k : r.mesh.removed) {
      EXPECT_EQ(mapper.mesh().submeshes().count(k), 0u) << k;
      streamed.erase(k);
    }
    for (const BlockKey& k : r.evicted_blocks) {
      EXPECT_EQ(mapper.mesh().submeshes().count(k), 0u)
          << "evicted block " << k << " kept its submesh";
      removed_by_eviction += std::binary_search(r.mesh.removed.begin(), r.mesh.removed.end(), k);
    }
  }
  EXPECT_GT(removed_by_eviction, 20u);
  ThreadPool pool(2);
  MeshStore batch(MeshingParams{config.voxel_size_m, config.truncation_vox,
                                config.mesh_level_min_coverage, config.mesh_fill_seams});
  batch.rebuild(mapper.tsdf(), &pool);
  ASSERT_GT(batch.triangleCount(), 1000u);
  EXPECT_TRUE(triangleSets(mapper.mesh()) == triangleSets(batch))
      << "incremental mesh differs from a rebuild";
  ASSERT_EQ(streamed.size(), mapper.mesh().submeshes().size());
  for (const auto& [key, sub] : mapper.mesh().submeshes()) {
    auto it = streamed.find(key);
    ASSERT_NE(it, streamed.end()) << key;
    EXPECT_EQ(it->second.positions, sub.positions) << key;
    EXPECT_EQ(it->second.triangles, sub.triangles) << key;
  }
}

TEST(MemoryBound, UnlimitedByDefaultEvictsNothing) {
  const sim::AnalyticScene scene = corridor();
  Mapper mapper(boundedConfig());
  for (int f = 0; f < 10; ++f)
    EXPECT_TRUE(mapper.integrate(corridorFrame(scene, 0.3 * f)).evicted_blocks.empty());
  EXPECT_EQ(mapper.blocksEvicted(), 0u);
}

TEST(MemoryBound, DistanceBoundBelowTheFusionRangeIsRefused) {
  MapperConfig config = boundedConfig();
  config.max_depth_m = 8.0;
  config.max_distance_from_camera_m = 3.0;
  const std::vector<std::string> errors = validateMapperConfig(config);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("max_distance_from_camera_m"), std::string::npos);
  config.max_distance_from_camera_m = 8.0;
  EXPECT_TRUE(validateMapperConfig(config).empty());
  config.max_distance_from_camera_m = 0.0;  // off
  EXPECT_TRUE(validateMapperConfig(config).empty());
}

// Meshing at its own rate with the memory bound on: frames fused with the mesh deferred, a
// meshing pass every third frame, give the same map and mesh as meshing after every frame,
// and that mesh equals a rebuild, although blocks are evicted (and their rows reused) between
// passes. The Mapper's running memory figure equals the octree's own count all along.
TEST(MemoryBound, DeferredMeshingWithEvictionEqualsMeshingEveryFrame) {
  const sim::AnalyticScene scene = corridor();
  MapperConfig config = boundedConfig();
  config.max_blocks = 250;
  Mapper every_frame(config), deferred(config);
  uint64_t evicted = 0;
  for (int f = 0; f < 24; ++f) {
    const StereoFrame frame = corridorFrame(scene, 0.15 * f);
    ASSERT_TRUE(every_frame.integrate(frame).accepted);
    const IntegrationResult r = deferred.integrate(frame, MeshTiming::kDeferred);
    ASSERT_TRUE(r.accepted);
    evicted += r.evicted_blocks.size();
    if (f % 3 == 2) deferred.updateMesh();
    EXPECT_EQ(deferred.memoryBytes(), deferred.tsdf().memoryBytes()) << "frame " << f;
  }
  deferred.updateMesh();
  EXPECT_GT(evicted, 100u);
  EXPECT_TRUE(snapshot(deferred.tsdf()) == snapshot(every_frame.tsdf()));
  EXPECT_TRUE(triangleSets(deferred.mesh()) == triangleSets(every_frame.mesh()));
  expectMeshEqualsRebuild(deferred);
}

// A reset reports every submesh as removed to the mesh's consumers, after what they have not
// taken yet (here removals by eviction): a consumer that mirrors the mesh ends empty.
TEST(MemoryBound, MeshConsumersMirrorTheMeshThroughEvictionAndReset) {
  const sim::AnalyticScene scene = corridor();
  MapperConfig config = boundedConfig();
  config.max_blocks = 250;
  Mapper mapper(config);
  const BlockChangeLog::Consumer mirror = mapper.subscribeToMeshChanges("mirror");
  std::set<BlockKey> held;
  auto apply = [&] {
    const BlockChangeLog::Changes c = mapper.takeMeshChanges(mirror);
    for (const BlockKey& k : c.updated) held.insert(k);
    for (const BlockKey& k : c.erased) held.erase(k);
  };
  size_t removed_pending = 0;
  for (int f = 0; f < 20; ++f) {
    const IntegrationResult r = mapper.integrate(corridorFrame(scene, 0.15 * f));
    ASSERT_TRUE(r.accepted);
    if (f < 17) {
      apply();
    } else {
      removed_pending += r.mesh.removed.size();  // left for the reset to come after
    }
  }
  EXPECT_GT(removed_pending, 0u);
  mapper.reset();
  apply();
  EXPECT_TRUE(held.empty()) << held.size() << " submeshes still held";
}
