// Mapper::clearRegion() (the ~clear_box / ~clear_sphere services): the surface inside the region
// goes, from the map and from the mesh (removed submeshes reported as such), everything outside
// stays bit-identical, the region can be observed again, and an invalid region changes nothing.
#include <gtest/gtest.h>

#include "MeshTestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

const Eigen::Vector3d kBallCentre(0.05, 0.1, 1.2);  // floorAndSphere()'s ball, radius 0.2 m

/// Mesh vertices within `radius_m` of `centre`.
size_t verticesNear(const Mapper& mapper, const Eigen::Vector3d& centre, double radius_m) {
  size_t n = 0;
  for (const auto& [key, sub] : mapper.mesh().submeshes())
    for (const Eigen::Vector3f& p : sub.positions)
      n += (p.cast<double>() - centre).norm() < radius_m;
  return n;
}

}  // namespace

TEST(ClearRegion, TheBallGoesFromMapAndMeshAndEverythingOutsideStaysBitIdentical) {
  std::unique_ptr<Mapper> mapper = fusedMapper(6);
  const MapSnapshot before = snapshot(mapper->tsdf());
  const size_t submeshes_before = mapper->mesh().submeshes().size();
  ASSERT_GT(verticesNear(*mapper, kBallCentre, 0.25), 500u);
  const BlockChangeLog::Consumer listener = mapper->subscribeToMeshChanges("test");

  const MapRegion region = MapRegion::sphere(kBallCentre, 0.35);
  const ClearResult result = mapper->clearRegion(region);
  ASSERT_TRUE(result.accepted) << result.error;
  EXPECT_GT(result.voxels_cleared, 1000u);
  EXPECT_GT(result.blocks_erased, 0u);
  EXPECT_GT(result.blocks_changed, 0u);

  // Voxel by voxel: inside the region unobserved, outside exactly as before.
  const MapSnapshot after = snapshot(mapper->tsdf());
  size_t compared = 0;
  for (size_t b = 0; b < before.keys.size(); ++b) {
    const BlockKey key = before.keys[b];
    const VoxelBlock* block = mapper->tsdf().find(key);
    for (int level = 0; level < kNumLevels; ++level) {
      const int side = levelSide(level);
      for (int k = 0; k < side; ++k)
        for (int j = 0; j < side; ++j)
          for (int i = 0; i < side; ++i) {
            const Voxel& old =
                before.voxels[b * VoxelBlock::kVoxelCount + VoxelBlock::index(level, i, j, k)];
            if (region.contains(voxelCentre(mapper->tsdf(), key, level, i, j, k))) {
              if (block) {
                EXPECT_EQ(block->at(level, i, j, k).weight, 0.0f);
              }
              continue;
            }
            if (old.weight == 0.0f) continue;
            ASSERT_NE(block, nullptr)
                << "block " << key << " with observed voxels outside the region was erased";
            const Voxel& now = block->at(level, i, j, k);
            EXPECT_TRUE(now.sdf_m == old.sdf_m && now.weight == old.weight && now.r == old.r)
                << key;
            ++compared;
          }
    }
  }
  EXPECT_GT(compared, 10000u);
  EXPECT_LT(after.keys.size(), before.keys.size());
  // Mapper::memoryBytes() keeps track of the freed levels without a walk.
  EXPECT_EQ(mapper->memoryBytes(), mapper->tsdf().memoryBytes());

  // A mesh vertex lies between two observed voxels: none is left inside the region (the segment
  // between two 8 cm voxel centres outside a 0.35 m sphere dips into it by < 3 mm).
  EXPECT_EQ(verticesNear(*mapper, kBallCentre, 0.34), 0u);
  EXPECT_GT(verticesNear(*mapper, kBallCentre, 1.0), 100u);  // the floor around it stays
  expectMeshEqualsRebuild(*mapper);
  // Consumers of the mesh hear of every submesh that went.
  const BlockChangeLog::Changes heard = mapper->takeMeshChanges(listener);
  EXPECT_FALSE(heard.erased.empty());
  EXPECT_EQ(heard.erased, result.mesh.removed);
  EXPECT_EQ(mapper->mesh().submeshes().size(), submeshes_before - result.mesh.removed.size());
}

TEST(ClearRegion, AClearedRegionIsUnknownAndLaterFramesFillItAgain) {
  std::unique_ptr<Mapper> mapper = fusedMapper(6);
  const size_t near_before = verticesNear(*mapper, kBallCentre, 0.25);
  ASSERT_TRUE(mapper
                  ->clearRegion(MapRegion::box(kBallCentre - Eigen::Vector3d::Constant(0.3),
                                               kBallCentre + Eigen::Vector3d::Constant(0.3)))
                  .accepted);
  EXPECT_EQ(verticesNear(*mapper, kBallCentre, 0.25), 0u);
  const sim::AnalyticScene scene = floorAndSphere();
  for (int i = 0; i < 6; ++i) {
    StereoFrame f = renderFrame(scene, qvgaCamera(), floorAndSphereView(i), 0.2, 100 + i);
    f.timestamp_s = 10.0 + i;
    ASSERT_TRUE(mapper->integrate(f).accepted);
  }
  EXPECT_GT(verticesNear(*mapper, kBallCentre, 0.25), near_before * 8 / 10);
  expectMeshEqualsRebuild(*mapper);
}

TEST(ClearRegion, DeferredMeshingWaitsForUpdateMeshLikeAFrame) {
  std::unique_ptr<Mapper> mapper = fusedMapper(4);
  const ClearResult result =
      mapper->clearRegion(MapRegion::sphere(kBallCentre, 0.3), MeshTiming::kDeferred);
  ASSERT_TRUE(result.accepted);
  EXPECT_TRUE(result.mesh.changed.empty() && result.mesh.removed.empty());
  EXPECT_EQ(mapper->blocksAwaitingMesh(), result.blocks_changed + result.blocks_erased);
  EXPECT_GT(verticesNear(*mapper, kBallCentre, 0.25), 0u);  // the mesh has not caught up yet
  mapper->updateMesh();
  EXPECT_EQ(verticesNear(*mapper, kBallCentre, 0.25), 0u);
  expectMeshEqualsRebuild(*mapper);
}

TEST(ClearRegion, AnInvalidRegionIsRefusedAndLeavesTheMapUntouched) {
  std::unique_ptr<Mapper> mapper = fusedMapper(3);
  const MapSnapshot before = snapshot(mapper->tsdf());
  const auto mesh_before = triangleSets(mapper->mesh());
  const ClearResult result = mapper->clearRegion(MapRegion::box({1, 0, 0}, {0, 1, 1}));
  EXPECT_FALSE(result.accepted);
  EXPECT_NE(result.error.find("min must not exceed its max"), std::string::npos) << result.error;
  EXPECT_TRUE(snapshot(mapper->tsdf()) == before);
  EXPECT_TRUE(triangleSets(mapper->mesh()) == mesh_before);
  EXPECT_EQ(mapper->blocksAwaitingMesh(), 0u);
}
