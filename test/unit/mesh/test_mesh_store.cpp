// MeshStore::update() by keys, as the Mapper's meshing passes call it with the change log's
// updated and erased blocks: it refreshes the mesher's state of the updated blocks, reaches
// owners through the neighbour links, and must give the submeshes of a from-scratch rebuild,
// before and after blocks are erased.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include "MeshTestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {
/// The exact SDF of a 0.25 m sphere off the block grid, at the finest level of every block near it.
void fillSphere(BlockOctree* map, double voxel_m) {
  sim::AnalyticScene scene;
  scene.add(sim::makeSphere({0.013, -0.021, 0.037}, 0.25));
  fillAnalytic(map, scene,
               Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-0.4), Eigen::Vector3d::Constant(0.4)),
               3 * voxel_m, [](const BlockKey&) { return 0; });
}
}  // namespace

TEST(MeshStore, UpdateByKeysEqualsARebuildBeforeAndAfterErase) {
  const double voxel_m = 0.02;
  BlockOctree map(8 * voxel_m);
  fillSphere(&map, voxel_m);
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

// Two submeshes sharing an edge, handed over out of key order: the weld keeps vertices in
// key order and first appearance, joins the bit-equal ones (colour of the first, normals summed
// then normalised) and re-indexes the second submesh's triangle onto them.
TEST(MeshStore, WeldJoinsBitEqualVerticesInKeyOrder) {
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> submeshes;
  SubMesh& a = submeshes[BlockKey{0, 0, 0}];
  a.key = BlockKey{0, 0, 0};
  a.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  a.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  a.colors = {{{10, 0, 0}}, {{11, 0, 0}}, {{12, 0, 0}}};
  a.triangles = {{{0, 1, 2}}};
  SubMesh& b = submeshes[BlockKey{1, 0, 0}];
  b.key = BlockKey{1, 0, 0};
  b.positions = {{1, 1, 0}, {0, 1, 0}, {1, 0, 0}};  // shares (1,0,0) and (0,1,0) with a
  b.normals = {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}};
  b.colors = {{{20, 0, 0}}, {{21, 0, 0}}, {{22, 0, 0}}};
  b.triangles = {{{0, 1, 2}}};
  const TriangleMesh mesh = weldSubmeshes(submeshes);
  ASSERT_EQ(mesh.positions.size(), 4u);
  EXPECT_EQ(mesh.positions[3], Eigen::Vector3f(1, 1, 0));  // b's only new vertex comes last
  EXPECT_EQ(mesh.colors[1][0], 11);                        // the first submesh's colour
  EXPECT_EQ(mesh.colors[3][0], 20);
  ASSERT_EQ(mesh.triangles.size(), 2u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(mesh.triangles[1], (std::array<uint32_t, 3>{3, 2, 1}));
  const float h = std::sqrt(0.5f);
  EXPECT_TRUE(mesh.normals[0].isApprox(Eigen::Vector3f(0, 0, 1)));
  EXPECT_TRUE(mesh.normals[1].isApprox(Eigen::Vector3f(h, 0, h)));  // (0,0,1) + (1,0,0)
  EXPECT_TRUE(mesh.normals[2].isApprox(Eigen::Vector3f(h, 0, h)));
  EXPECT_TRUE(mesh.normals[3].isApprox(Eigen::Vector3f(1, 0, 0)));
}

// Kept submeshes hold their bytes, not the capacity a push_back-grown array would leave.
TEST(MeshStore, KeepsSubmeshesAtTheirSize) {
  const double voxel_m = 0.02;
  BlockOctree map(8 * voxel_m);
  fillSphere(&map, voxel_m);
  ThreadPool pool(2);
  MeshStore store(MeshingParams{voxel_m, 4.0, 0.8});
  store.rebuild(map, &pool);
  ASSERT_GT(store.submeshes().size(), 50u);
  size_t data_bytes = 0;
  for (const auto& [key, m] : store.submeshes()) {
    EXPECT_EQ(m.positions.capacity(), m.positions.size());
    EXPECT_EQ(m.normals.capacity(), m.normals.size());
    EXPECT_EQ(m.colors.capacity(), m.colors.size());
    EXPECT_EQ(m.triangles.capacity(), m.triangles.size());
    data_bytes += m.positions.size() * 27 + m.triangles.size() * 12;
  }
  EXPECT_GE(store.memoryBytes(), data_bytes);
  EXPECT_LT(store.memoryBytes(), data_bytes + 512 * store.submeshes().size());
}
