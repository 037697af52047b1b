// MeshFollower: the rviz display's copy of ~mesh_update (no master, no rviz). Replace, remove,
// empty blocks, full meshes, sessions, sequence gaps, the fetch of a full mesh and what it marks
// for redrawing.
#include <gtest/gtest.h>

#include <algorithm>

#include "stereo_fusion/ros/MeshFollower.h"
#include "stereo_fusion/ros/MeshMessages.h"

using namespace stereo_fusion;
using Outcome = MeshFollower::Outcome;

namespace {

constexpr uint64_t kSession = 1000;

/// A block at `key` with `triangles` triangles (a fan over triangles + 2 vertices), its vertices
/// tagged with red = `tag` so a test can tell two versions of a block apart.
MeshBlock block(BlockKey key, int triangles, uint8_t tag = 0) {
  MeshBlock b;
  b.key = {key.x, key.y, key.z};
  const int vertices = triangles > 0 ? triangles + 2 : 0;
  for (int v = 0; v < vertices; ++v) {
    b.vertices.insert(b.vertices.end(), {0.16f * key.x + 0.01f * v, 0.16f * key.y, 0.16f * key.z});
    b.normals.insert(b.normals.end(), {0.0f, 0.0f, 1.0f});
    b.colors.insert(b.colors.end(), {tag, 0, 0});
  }
  for (int t = 0; t < triangles; ++t)
    b.triangles.insert(b.triangles.end(), {0u, uint32_t(t + 1), uint32_t(t + 2)});
  return b;
}

MeshUpdate update(uint64_t sequence, std::vector<MeshBlock> blocks,
                  std::vector<BlockKey> removed = {}, bool full = false,
                  uint64_t session = kSession) {
  MeshUpdate u;
  u.header.frame_id = "map";
  u.sequence = sequence;
  u.session = session;
  u.full = full;
  u.voxel_size = 0.02f;
  u.block_size = 0.16f;
  u.blocks = std::move(blocks);
  for (const BlockKey& k : removed) u.removed_keys.insert(u.removed_keys.end(), {k.x, k.y, k.z});
  return u;
}

std::vector<BlockKey> sorted(std::vector<BlockKey> keys) {
  std::sort(keys.begin(), keys.end());
  return keys;
}

const BlockKey kA{0, 0, 0}, kB{1, 0, 0}, kC{0, -1, 2};

size_t trianglesOf(const MeshFollower& f, BlockKey key) {
  auto it = f.mesh().find(key);
  return it == f.mesh().end() ? 0 : it->second.triangles.size();
}

uint8_t tagOf(const MeshFollower& f, BlockKey key) { return f.mesh().at(key).colors.at(0)[0]; }

}  // namespace

TEST(MeshFollower, ABlockReplacesItsOldSubmeshAndOnlyChangedBlocksAreDirty) {
  MeshFollower f;
  ASSERT_EQ(f.update(update(1, {block(kA, 4, 1), block(kB, 2, 1)}, {}, true)), Outcome::kApplied);
  EXPECT_EQ(sorted(f.takeDirty()), sorted({kA, kB}));
  EXPECT_TRUE(f.takeDirty().empty()) << "taking the dirty keys clears them";

  ASSERT_EQ(f.update(update(2, {block(kA, 1, 2)})), Outcome::kApplied);
  EXPECT_EQ(trianglesOf(f, kA), 1u) << "replaced, not appended to";
  EXPECT_EQ(tagOf(f, kA), 2);
  EXPECT_EQ(trianglesOf(f, kB), 2u) << "a block the update does not carry stays as it was";
  EXPECT_EQ(tagOf(f, kB), 1);
  EXPECT_EQ(f.takeDirty(), std::vector<BlockKey>{kA});
  EXPECT_TRUE(f.synced());
  EXPECT_EQ(f.lastSequence(), 2u);
}

TEST(MeshFollower, RemovedKeysAndEmptyBlocksEraseTheirSubmesh) {
  MeshFollower f;
  f.update(update(1, {block(kA, 4), block(kB, 2), block(kC, 3)}, {}, true));
  f.takeDirty();
  ASSERT_EQ(f.update(update(2, {block(kB, 0)}, {kA})), Outcome::kApplied);
  EXPECT_EQ(f.mesh().count(kA), 0u) << "in removed_keys";
  EXPECT_EQ(f.mesh().count(kB), 0u) << "a block without triangles is no submesh";
  EXPECT_EQ(trianglesOf(f, kC), 3u);
  EXPECT_EQ(sorted(f.takeDirty()), sorted({kA, kB})) << "both drawings must go";
  // Removing a key that is not held is harmless (a removal of a block never meshed).
  ASSERT_EQ(f.update(update(3, {}, {kA})), Outcome::kApplied);
  EXPECT_EQ(f.mesh().size(), 1u);
}

TEST(MeshFollower, AFullUpdateResetsEverythingHeldAndMarksTheOldBlocksDirty) {
  MeshFollower f;
  f.update(update(1, {block(kA, 4), block(kB, 2)}, {}, true));
  f.update(update(2, {block(kC, 1)}));
  f.takeDirty();
  // ~reset on the robot: its next update is full with an empty (or new) mesh.
  ASSERT_EQ(f.update(update(3, {block(kB, 5, 7)}, {}, true)), Outcome::kApplied);
  EXPECT_EQ(f.mesh().size(), 1u);
  EXPECT_EQ(trianglesOf(f, kB), 5u);
  EXPECT_EQ(sorted(f.takeDirty()), sorted({kA, kB, kC}))
      << "A and C were dropped by the full update: their drawings must go";
  ASSERT_EQ(f.update(update(4, {}, {}, true)), Outcome::kApplied);
  EXPECT_TRUE(f.mesh().empty()) << "an empty full update clears the copy";
  EXPECT_EQ(f.takeDirty(), std::vector<BlockKey>{kB});
}

TEST(MeshFollower, AFullMeshOlderThanTheCopyAndRepeatedUpdatesAreIgnored) {
  MeshFollower f;
  f.update(update(5, {block(kA, 4)}, {}, true));
  f.update(update(6, {block(kB, 2)}));
  f.takeDirty();
  EXPECT_EQ(f.update(update(6, {block(kB, 9)})), Outcome::kIgnoredOld);
  EXPECT_EQ(f.update(update(4, {block(kC, 1)}, {}, true)), Outcome::kIgnoredOld)
      << "a late full mesh of the same run would undo update 6";
  EXPECT_EQ(trianglesOf(f, kB), 2u);
  EXPECT_EQ(f.mesh().count(kC), 0u);
  EXPECT_TRUE(f.takeDirty().empty());
  EXPECT_EQ(f.ignoredOld(), 2u);
  EXPECT_TRUE(f.synced());
}

TEST(MeshFollower, AGapIsCountedDrawnAsItComesAndRepairedByTheFullMesh) {
  MeshFollower f;
  f.update(update(1, {block(kA, 4)}, {}, true));
  ASSERT_FALSE(f.wantsFullMesh());
  // Updates 2 and 3 are lost; 3 removed A and added C.
  ASSERT_EQ(f.update(update(4, {block(kB, 2)})), Outcome::kBestEffort);
  EXPECT_EQ(f.gaps(), 2u);
  EXPECT_FALSE(f.synced());
  EXPECT_TRUE(f.wantsFullMesh());
  EXPECT_EQ(trianglesOf(f, kB), 2u) << "its blocks are right, so they are drawn";
  f.takeDirty();

  f.fetchStarted();
  EXPECT_FALSE(f.wantsFullMesh()) << "one fetch at a time";
  EXPECT_EQ(f.update(update(5, {block(kB, 3)})), Outcome::kQueued);
  EXPECT_EQ(f.update(update(6, {block(kA, 1, 6)})), Outcome::kQueued);
  EXPECT_EQ(trianglesOf(f, kB), 2u) << "queued, not applied, while the full mesh is on its way";
  // The full mesh was taken at sequence 5: it holds update 5 but not 6.
  ASSERT_EQ(f.fullMeshArrived(update(5, {block(kB, 3), block(kC, 1)})), Outcome::kApplied);
  EXPECT_TRUE(f.synced());
  EXPECT_EQ(f.lastSequence(), 6u) << "update 6, queued, follows the full mesh";
  EXPECT_EQ(trianglesOf(f, kA), 1u);
  EXPECT_EQ(tagOf(f, kA), 6);
  EXPECT_EQ(trianglesOf(f, kB), 3u);
  EXPECT_EQ(trianglesOf(f, kC), 1u);
  EXPECT_EQ(f.ignoredOld(), 1u) << "update 5 was already in the full mesh";
  EXPECT_EQ(sorted(f.takeDirty()), sorted({kA, kB, kC}));
}

TEST(MeshFollower, AFailedFetchAppliesTheQueuedUpdatesAndAsksAgain) {
  MeshFollower f;
  ASSERT_EQ(f.update(update(7, {block(kA, 4)})), Outcome::kBestEffort)
      << "joined late: the first update is drawn, but the rest of the mesh is missing";
  EXPECT_TRUE(f.wantsFullMesh());
  f.fetchStarted();
  EXPECT_EQ(f.update(update(8, {block(kB, 2)})), Outcome::kQueued);
  f.fetchFailed();
  EXPECT_EQ(trianglesOf(f, kB), 2u);
  EXPECT_EQ(f.lastSequence(), 8u);
  EXPECT_TRUE(f.wantsFullMesh()) << "still not the robot's mesh";
}

TEST(MeshFollower, TheQueueWhileFetchingIsBoundedAndItsDropsCounted) {
  MeshFollower f;
  f.update(update(1, {block(kA, 1)}));
  f.fetchStarted();
  const size_t sent = MeshFollower::kMaxQueued + 5;
  for (size_t i = 0; i < sent; ++i) f.update(update(2 + i, {block(kB, 1)}));
  EXPECT_EQ(f.queueDropped(), 5u);
  f.fullMeshArrived(update(1 + sent, {block(kA, 1), block(kB, 2)}));
  EXPECT_TRUE(f.synced()) << "the full mesh covers every queued update, dropped ones too";
  EXPECT_EQ(trianglesOf(f, kB), 2u);
}

TEST(MeshFollower, ARestartOfThePublisherDropsTheOldRunsMesh) {
  MeshFollower f;
  f.update(update(40, {block(kA, 4), block(kB, 2)}, {}, true));
  f.takeDirty();
  // The robot's nodelet restarted: sequence 1 again, a new session, a map rebuilt from nothing.
  ASSERT_EQ(f.update(update(1, {block(kC, 1)}, {}, false, kSession + 1)), Outcome::kBestEffort);
  EXPECT_EQ(f.restarts(), 1u);
  EXPECT_EQ(f.mesh().size(), 1u) << "A and B were the old run's";
  EXPECT_EQ(trianglesOf(f, kC), 1u);
  EXPECT_EQ(sorted(f.takeDirty()), sorted({kA, kB, kC}));
  EXPECT_TRUE(f.wantsFullMesh());
  EXPECT_EQ(f.update(update(2, {block(kA, 1)}, {}, false, kSession + 1)), Outcome::kBestEffort)
      << "the new run's next update is not a repeat of the old run's 40";
  EXPECT_EQ(f.session(), kSession + 1);
}

TEST(MeshFollower, AMalformedUpdateChangesNothingAndAsksForTheFullMesh) {
  MeshFollower f;
  f.update(update(1, {block(kA, 4)}, {}, true));
  f.takeDirty();
  MeshBlock bad = block(kB, 2);
  bad.triangles.back() = 99;  // index out of range
  EXPECT_EQ(f.update(update(2, {block(kA, 1), bad})), Outcome::kMalformed);
  EXPECT_EQ(trianglesOf(f, kA), 4u) << "refused as a whole";
  EXPECT_EQ(f.mesh().count(kB), 0u);
  EXPECT_TRUE(f.takeDirty().empty());
  EXPECT_EQ(f.malformed(), 1u);
  EXPECT_TRUE(f.wantsFullMesh());
}

TEST(MeshFollower, CompactBlocksAreDecodedAsTheAssemblerDecodesThem) {
  // The same submesh through the compact encoding: MeshFollower uses applyMeshUpdate.
  MeshUpdate u = update(1, {}, {}, true);
  SubMesh s;
  s.key = kB;
  s.positions = {{0.17f, 0.01f, 0.02f}, {0.2f, 0.05f, 0.02f}, {0.19f, 0.1f, 0.1f}};
  s.normals.assign(3, Eigen::Vector3f(0, 0, 1));
  s.colors.assign(3, {10, 20, 30});
  s.triangles = {{0, 1, 2}};
  u.blocks.push_back(toMeshBlock(s, MeshEncoding::kCompact, u.block_size));
  ASSERT_GT(u.blocks[0].position_step_m, 0.0f);
  MeshFollower f;
  ASSERT_EQ(f.update(u), Outcome::kApplied);
  const SubMesh& held = f.mesh().at(kB);
  ASSERT_EQ(held.positions.size(), 3u);
  for (size_t v = 0; v < 3; ++v)
    EXPECT_LE((held.positions[v] - s.positions[v]).norm(), u.blocks[0].position_step_m);
}

TEST(MeshFollower, ResetForgetsEverythingAndStartsOver) {
  MeshFollower f;
  f.update(update(3, {block(kA, 4), block(kB, 1)}, {}, true));
  f.takeDirty();
  f.reset();
  EXPECT_TRUE(f.mesh().empty());
  EXPECT_EQ(sorted(f.takeDirty()), sorted({kA, kB}));
  EXPECT_TRUE(f.wantsFullMesh());
  EXPECT_EQ(f.update(update(2, {block(kC, 1)})), Outcome::kBestEffort)
      << "after a reset no sequence is held: an older number is not ignored";
}
