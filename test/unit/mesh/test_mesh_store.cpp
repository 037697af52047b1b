// MeshStore::update() by keys, as the Mapper's meshing passes call it with the change log's
// updated and erased blocks: it refreshes the mesher's state of the updated blocks, reaches
// owners through the neighbour links, and must give the submeshes of a from-scratch rebuild,
// before and after blocks are erased.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "MeshTestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

TEST(MeshStore, UpdateByKeysEqualsARebuildBeforeAndAfterErase) {
  const double voxel_m = 0.02;
  BlockOctree map(8 * voxel_m);
  sim::AnalyticScene scene;
  scene.add(sim::makeSphere({0.013, -0.021, 0.037}, 0.25));
  fillAnalytic(&map, scene,
               Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-0.4), Eigen::Vector3d::Constant(0.4)),
               3 * voxel_m, [](const BlockKey&) { return 0; });
  ASSERT_GT(map.blockCount(), 100u);
  ThreadPool pool(2);
  const MeshingParams params{voxel_m, 4.0, 0.8};
  MeshStore by_key(params);

  std::vector<BlockKey> keys;
  for (const VoxelBlock* b : map.blocksSortedByKey()) keys.push_back(b->key);
  const size_t blocks = keys.size();
  keys.push_back({100, 100, 100});  // no block there, nor at its owners: changes nothing
  const MeshChanges first_by_key = by_key.update(map, keys, &pool);
  EXPECT_EQ(first_by_key.blocks_meshed, map.blockCount());  // every block owns its own cells
  EXPECT_GT(first_by_key.changed.size(), 40u);
  EXPECT_TRUE(first_by_key.removed.empty());
  MeshStore first_rebuild(params);
  const MeshChanges rebuilt_changes = first_rebuild.rebuild(map, &pool);
  EXPECT_EQ(first_by_key.changed, rebuilt_changes.changed);
  EXPECT_TRUE(triangleSets(by_key) == triangleSets(first_rebuild));

  // Erase every third block with a surface: their submeshes go, their owners are re-meshed.
  std::vector<BlockKey> erased;
  for (size_t i = 0; i < first_by_key.changed.size(); i += 3)
    erased.push_back(first_by_key.changed[i]);
  ASSERT_EQ(map.erase(erased), erased.size());
  const MeshChanges second_by_key = by_key.update(map, {}, &pool, erased);
  for (const BlockKey& k : erased)
    EXPECT_TRUE(std::binary_search(second_by_key.removed.begin(), second_by_key.removed.end(), k))
        << k;
  // Up to 7 surviving owners per erased block, shared between neighbours.
  EXPECT_GT(second_by_key.blocks_meshed, erased.size());
  EXPECT_LE(second_by_key.blocks_meshed, 7 * erased.size());

  std::printf(
      "[ mesh store ] %zu blocks, %zu submeshes; %zu erased: %zu owners re-meshed, %zu removed\n",
      blocks, first_by_key.changed.size(), erased.size(), second_by_key.blocks_meshed,
      second_by_key.removed.size());

  MeshStore rebuilt(params);
  rebuilt.rebuild(map, &pool);
  EXPECT_TRUE(triangleSets(by_key) == triangleSets(rebuilt));
  EXPECT_EQ(by_key.submeshes().size(), rebuilt.submeshes().size());
  EXPECT_LE(by_key.submeshes().size(), first_by_key.changed.size() - erased.size());
}
