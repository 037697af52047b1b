// Meshing of fused analytic objects: watertight across blocks and resolution changes,
// incremental == batch, accurate, deterministic.
#include <gtest/gtest.h>

#include <algorithm>

#include "MeshTestSupport.h"
#include "QuickMode.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

constexpr double kVoxel = 0.02;
const Eigen::Vector3d kCentre(0.013, -0.021, 0.037);  // off the block grid on purpose

MeshingParams meshingParams() { return {kVoxel, 4.0, 0.8}; }

sim::AnalyticScene sphereScene() {
  sim::AnalyticScene s;
  s.add(sim::makeSphere(kCentre, 0.25));
  return s;
}
sim::AnalyticScene boxScene() {
  sim::AnalyticScene s;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translate(kCentre);
  T.rotate(Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 0.5).normalized()));
  s.add(sim::makeBox(T, {0.2, 0.15, 0.12}));
  return s;
}
sim::AnalyticScene torusScene() {
  sim::AnalyticScene s;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translate(kCentre);
  T.rotate(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 0, 0.3).normalized()));
  s.add(sim::makeTorus(T, 0.24, 0.09));
  return s;
}

/// Forgets the finer levels of the blocks selected by `coarse_level(key)` (> 0): as if
/// those blocks had only been seen from far away.
void forgetFineLevels(const Mapper& mapper,
                      const std::function<int(const BlockKey&)>& coarse_level) {
  for (VoxelBlock* b : mapper.tsdf().blocks()) {
    const int keep_from = coarse_level(b->key);
    for (int level = 0; level < keep_from; ++level) b->releaseLevel(level);
  }
}

/// The welded mesh of fused `scene` whose blocks keep only the levels from `coarse_level(key)`
/// up, meshed with or without the seam fill.
Topology fusedTopology(const char* name, const sim::AnalyticScene& scene,
                       const std::function<int(const BlockKey&)>& coarse_level,
                       std::set<int> expected_levels, bool fill_seams,
                       double truncation_vox = 4.0) {
  // 1e-6: every block meshes at the finest level holding any data, i.e. at the level the
  // test leaves it (the default 0.8 may keep a barely touched block coarse).
  MapperConfig config;
  config.voxel_size_m = kVoxel;
  config.truncation_vox = truncation_vox;
  auto mapper = fuseViews(scene, viewsAround(kCentre, 1.0, 60), config);
  forgetFineLevels(*mapper, coarse_level);
  ThreadPool pool(2);
  MeshingParams params{kVoxel, truncation_vox, 1e-6};
  params.fill_faces_from_coarser_levels = fill_seams;
  MeshStore store(params);
  store.rebuild(mapper->tsdf(), &pool);
  std::set<int> levels;
  for (const auto& [key, sub] : store.submeshes()) levels.insert(sub.level);
  EXPECT_EQ(levels, expected_levels) << name;
  const Topology t = topology(weldSubmeshes(store.submeshes()));
  std::printf("[ watertight ] %-28s %-12s %zu submeshes: %s\n", name,
              fill_seams ? "seams filled" : "no seam fill", store.submeshes().size(),
              describe(t).c_str());
  return t;
}

void expectWatertight(const char* name, const sim::AnalyticScene& scene,
                      const std::function<int(const BlockKey&)>& coarse_level,
                      std::set<int> expected_levels, double truncation_vox = 4.0) {
  const Topology t =
      fusedTopology(name, scene, coarse_level, expected_levels, true, truncation_vox);
  EXPECT_TRUE(t.watertight()) << name << ": " << describe(t);
}

}  // namespace

TEST(BlockMesher, SphereIsWatertightAtOneLevel) {
  expectWatertight("sphere, 8^3", sphereScene(), [](const BlockKey&) { return 0; }, {0});
}

TEST(BlockMesher, BoxIsWatertightAtOneLevel) {
  expectWatertight("box, 8^3", boxScene(), [](const BlockKey&) { return 0; }, {0});
}

TEST(BlockMesher, TorusIsWatertightAtOneLevel) {
  expectWatertight("torus, 8^3", torusScene(), [](const BlockKey&) { return 0; }, {0});
}

TEST(BlockMesher, WatertightAcrossAResolutionChange) {
  // Half of each object (blocks with x ≥ 0) is meshed at 4³, the rest at 8³.
  auto half = [](const BlockKey& k) { return k.x >= 0 ? 1 : 0; };
  expectWatertight("sphere, 8^3 | 4^3", sphereScene(), half, {0, 1});
  expectWatertight("box, 8^3 | 4^3", boxScene(), half, {0, 1});
  expectWatertight("torus, 8^3 | 4^3", torusScene(), half, {0, 1});
}

TEST(BlockMesher, FusedFineBlocksMeetTwoCubedBlocksWithoutHoles) {
  // Half of each object keeps only its 2³ level (seen from far), the rest keeps all three and
  // meshes at 8³. Where the fine band is thinner than a 2³ seam cell, the fine block's face
  // voxels are unobserved: without the seam fill those cells are skipped (holes along the
  // seam); filled from the fine block's own 2³ level, the mesh closes.
  auto half = [](const BlockKey& k) { return k.x >= 0 ? 2 : 0; };
  const std::pair<const char*, sim::AnalyticScene> shapes[] = {{"sphere, 8^3 | 2^3", sphereScene()},
                                                               {"box, 8^3 | 2^3", boxScene()},
                                                               {"torus, 8^3 | 2^3", torusScene()}};
  size_t open_without_fill = 0;
  for (const auto& [name, scene] : shapes) {
    const Topology filled = fusedTopology(name, scene, half, {0, 2}, /*fill_seams=*/true);
    EXPECT_TRUE(filled.watertight()) << name << ": " << describe(filled);
    open_without_fill +=
        fusedTopology(name, scene, half, {0, 2}, /*fill_seams=*/false).boundary_edges;
  }
  EXPECT_GT(open_without_fill, 0u)
      << "the seams must have holes to close, or this test shows nothing";
}

TEST(BlockMesher, WatertightAcrossAllThreeLevelsInACheckerboard) {
  // The mesher's own guarantee, separated from fusion: every block holds the exact SDF at a
  // level picked from its key, so 8³, 4³ and 2³ blocks meet on every face, edge and corner,
  // 8³ next to 2³ included, and every sample is observed. Any open or doubled edge would be a
  // crack or overlap made by the mesher. (With fused data, see
  // FusedFineBlocksMeetTwoCubedBlocksWithoutHoles.)
  auto mixed = [](const BlockKey& k) { return ((k.x + 2 * k.y + 3 * k.z) % 3 + 3) % 3; };
  const Eigen::AlignedBox3d bounds(kCentre - Eigen::Vector3d::Constant(0.5),
                                   kCentre + Eigen::Vector3d::Constant(0.5));
  const std::pair<const char*, sim::AnalyticScene> shapes[] = {
      {"sphere", sphereScene()}, {"box", boxScene()}, {"torus", torusScene()}};
  for (const auto& [name, scene] : shapes) {
    BlockOctree map(8 * kVoxel);
    fillAnalytic(&map, scene, bounds, 0.2, mixed);
    ThreadPool pool(2);
    MeshStore store(MeshingParams{kVoxel, 4.0, 1e-6});
    store.rebuild(map, &pool);
    std::set<int> levels;
    for (const auto& [key, sub] : store.submeshes()) levels.insert(sub.level);
    EXPECT_EQ(levels, (std::set<int>{0, 1, 2})) << name;
    const TriangleMesh mesh = weldSubmeshes(store.submeshes());
    const Topology t = topology(mesh);
    std::printf("[ watertight ] %-6s exact SDF, 8^3/4^3/2^3 checkerboard: %s\n", name,
                describe(t).c_str());
    EXPECT_TRUE(t.watertight()) << name << ": " << describe(t);
    // And the surface is where it should be, to within the coarsest level's resolution.
    double worst = 0;
    for (const auto& p : mesh.positions)
      worst = std::max(worst, scene.distanceToSurface(p.cast<double>()));
    EXPECT_LT(worst, 4 * kVoxel) << name;
  }
}

TEST(BlockMesher, SphereVerticesAndNormalsAreAccurate) {
  auto mapper = fuseViews(sphereScene(), viewsAround(kCentre, 1.0, 40));
  ThreadPool pool(2);
  MeshStore store(meshingParams());
  store.rebuild(mapper->tsdf(), &pool);
  const TriangleMesh mesh = weldSubmeshes(store.submeshes());
  ASSERT_GT(mesh.positions.size(), 1000u);
  std::vector<double> distance_vox, angle_deg;
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const Eigen::Vector3d p = mesh.positions[v].cast<double>();
    distance_vox.push_back(std::abs((p - kCentre).norm() - 0.25) / kVoxel);
    const Eigen::Vector3d truth = (p - kCentre).normalized();  // outward: towards free space
    angle_deg.push_back(
        std::acos(std::clamp(truth.dot(mesh.normals[v].cast<double>()), -1.0, 1.0)) * 180.0 / M_PI);
  }
  const double med_d = median(distance_vox), med_a = median(angle_deg);
  std::printf(
      "[ sphere mesh ] %zu vertices: median distance %.4f voxel, median normal error %.2f deg\n",
      mesh.positions.size(), med_d, med_a);
  EXPECT_LE(med_d, 0.1);
  EXPECT_LE(med_a, 5.0);
}

TEST(BlockMesher, SkipsUnobservedCellsAndEmptySpace) {
  // A single plane seen once: the mesh is an open sheet, and blocks holding only free space
  // produce no triangles.
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 1.2}, {0, 0, -1}));
  MapperConfig config;
  config.histogram_min_points = 0;
  Mapper mapper(config);
  ASSERT_TRUE(
      mapper.integrate(renderFrame(scene, qvgaCamera(), Eigen::Isometry3d::Identity())).accepted);
  const TriangleMesh mesh = mapper.extractMesh();
  ASSERT_GT(mesh.triangles.size(), 100u);
  for (const auto& p : mesh.positions) EXPECT_NEAR(p.z(), 1.2, 0.2 * kVoxel);
  const Topology t = topology(mesh);
  EXPECT_GT(t.boundary_edges, 0u);  // an open sheet: its rim is a boundary
  EXPECT_EQ(t.overused_edges, 0u);
  EXPECT_LT(mapper.mesh().submeshes().size(), mapper.tsdf().blockCount());
}

TEST(BlockMesher, IncrementalEqualsBatchAfterRandomPartialViews) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0.35, 0}, {0, -1, 0}));
  scene.add(sim::makeSphere({0.1, 0.1, 1.3}, 0.2));
  Eigen::Isometry3d box = Eigen::Isometry3d::Identity();
  box.translate(Eigen::Vector3d(-0.35, 0.2, 1.5));
  scene.add(sim::makeBox(box, {0.12, 0.15, 0.12}));
  MapperConfig config;
  config.voxel_size_m = kVoxel;
  Mapper mapper(config);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int f = 0; f < 8; ++f) {
    const Eigen::Vector3d eye(0.6 * u(rng), -0.3 + 0.2 * u(rng), 0.4 * u(rng));
    const Eigen::Vector3d target(0.3 * u(rng), 0.1, 1.4 + 0.2 * u(rng));
    const IntegrationResult r = mapper.integrate(renderFrame(
        scene, qvgaCamera(), sim::lookAt(eye, target, -Eigen::Vector3d::UnitY()), 0.2, f));
    ASSERT_TRUE(r.accepted);
    EXPECT_GT(r.mesh.blocks_meshed, 0u);
  }
  ThreadPool pool(2);
  MeshStore batch(MeshingParams{config.voxel_size_m, config.truncation_vox,
                                config.mesh_level_min_coverage, config.mesh_fill_seams});
  batch.rebuild(mapper.tsdf(), &pool);
  ASSERT_GT(batch.triangleCount(), 1000u);
  EXPECT_EQ(mapper.mesh().triangleCount(), batch.triangleCount());
  EXPECT_TRUE(triangleSets(mapper.mesh()) == triangleSets(batch))
      << "incremental mesh differs from a from-scratch extraction";
}

TEST(BlockMesher, RemeshingTouchesExactlyTheOwnersOfTheUpdatedBlocks) {
  sim::AnalyticScene scene;
  scene.add(sim::makeSphere({0.0, 0.0, 1.2}, 0.2));
  // A wall behind that the second view sees only in part: blocks it does not update border
  // blocks it does.
  scene.add(sim::makePlane({0.0, 0.0, 1.8}, {0.0, 0.0, -1.0}));
  Mapper mapper(MapperConfig{});
  ASSERT_TRUE(
      mapper.integrate(renderFrame(scene, qvgaCamera(), Eigen::Isometry3d::Identity())).accepted);
  const IntegrationResult r = mapper.integrate(renderFrame(
      scene, qvgaCamera(), sim::lookAt({0.3, 0, 0}, {0, 0, 1.2}, -Eigen::Vector3d::UnitY())));
  ASSERT_TRUE(r.accepted);
  // Independently: owners whose seams reach an updated block are K − (0|1, 0|1, 0|1).
  std::set<std::tuple<int, int, int>> expected;
  for (const BlockKey& k : r.updated_blocks)
    for (int dz = 0; dz <= 1; ++dz)
      for (int dy = 0; dy <= 1; ++dy)
        for (int dx = 0; dx <= 1; ++dx)
          if (mapper.tsdf().find(k.offset(-dx, -dy, -dz)))
            expected.insert({k.x - dx, k.y - dy, k.z - dz});
  EXPECT_EQ(r.mesh.blocks_meshed, expected.size());
  EXPECT_GT(expected.size(), r.updated_blocks.size());
  EXPECT_LT(r.mesh.blocks_meshed, mapper.tsdf().blockCount() + 1);
  for (const BlockKey& k : r.mesh.changed) EXPECT_TRUE(expected.count({k.x, k.y, k.z}));
  for (const BlockKey& k : r.mesh.removed) EXPECT_TRUE(expected.count({k.x, k.y, k.z}));
  // Each owner once, in key order (the parallel claims must not take one twice).
  for (const auto* keys : {&r.mesh.changed, &r.mesh.removed}) {
    EXPECT_TRUE(std::is_sorted(keys->begin(), keys->end()));
    EXPECT_TRUE(std::adjacent_find(keys->begin(), keys->end()) == keys->end());
  }
}

TEST(BlockMesher, RemeshingAnIsolatedBlockHandWorked) {
  // One block alone: updating it re-meshes only itself (its −x/−y/−z owners do not exist);
  // with its −x neighbour present, both.
  BlockOctree map(0.16);
  VoxelBlock* a = map.findOrAllocate({3, 3, 3});
  EXPECT_EQ(MeshStore::affectedOwners(map, {a->key}).size(), 1u);
  map.findOrAllocate({2, 3, 3});
  map.findOrAllocate({4, 3, 3});  // +x neighbour: not an owner of a's seams
  map.findOrAllocate({2, 2, 2});  // the −x−y−z diagonal: an owner
  const auto owners = MeshStore::affectedOwners(map, {a->key});
  ASSERT_EQ(owners.size(), 3u);
  EXPECT_EQ(owners[0], (BlockKey{2, 2, 2}));
  EXPECT_EQ(owners[1], (BlockKey{2, 3, 3}));
  EXPECT_EQ(owners[2], (BlockKey{3, 3, 3}));
}

TEST(BlockMesher, ThreadCountDoesNotChangeTheMesh) {
  std::optional<std::map<BlockKey, std::multiset<std::array<float, 9>>>> reference;
  for (int threads : {1, 2, 4}) {
    MapperConfig config;
    config.num_threads = threads;
    Mapper mapper(config);
    for (const auto& pose : viewsAround(kCentre, 1.0, quickMode() ? 3 : 5))
      ASSERT_TRUE(mapper.integrate(renderFrame(torusScene(), qvgaCamera(), pose)).accepted);
    const auto sets = triangleSets(mapper.mesh());
    if (!reference)
      reference = sets;
    else
      EXPECT_TRUE(sets == *reference) << threads << " threads";
  }
  EXPECT_FALSE(reference->empty());
}

TEST(BlockMesher, ColoursComeFromTheFusedVoxels) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 1.0}, {0, 0, -1}), {200, 100, 50});
  Mapper mapper(MapperConfig{});
  StereoFrame frame = renderFrame(scene, qvgaCamera(), Eigen::Isometry3d::Identity());
  frame.color.setTo(cv::Scalar(200, 100, 50));  // flat colour: every vertex must carry it
  ASSERT_TRUE(mapper.integrate(frame).accepted);
  const TriangleMesh mesh = mapper.extractMesh();
  ASSERT_FALSE(mesh.colors.empty());
  for (const auto& c : mesh.colors) {
    EXPECT_EQ(c[0], 200);
    EXPECT_EQ(c[1], 100);
    EXPECT_EQ(c[2], 50);
  }
}

TEST(BlockMesher, SignBitsPerRegionHandWorked) {
  // Level 0 (step 1): a voxel is near a low face when its centre 2i+1 < 8 half-voxels, i ≤ 3.
  // Observed voxels: (0,0,0) = −0.1 (near on x, y, z), (3,7,0) = +0.2 (near on x and z),
  // (4,4,4) = −0.3 (near on none), (7,0,7) = 0 (near on y; 0 counts as ≥ 0), and an
  // unobserved (1,1,1) = +5 that must not count.
  VoxelBlock block;
  MeshBlockState state;
  state.level = 0;
  auto set = [&](int i, int j, int k, float sdf, float weight) {
    block.writableAt(0, i, j, k).sdf_m = sdf;
    block.writableAt(0, i, j, k).weight = weight;
  };
  set(0, 0, 0, -0.1f, 1.0f);
  set(3, 7, 0, 0.2f, 1.0f);
  set(4, 4, 4, -0.3f, 2.0f);
  set(7, 0, 7, 0.0f, 1.0f);
  set(1, 1, 1, 5.0f, 0.0f);
  refreshMeshSigns(block, &state);
  auto has = [&](int region, bool non_negative) {
    return (state.sign_bits & meshSignBit(region, non_negative)) != 0;
  };
  // region: bit 0 x, bit 1 y, bit 2 z        <0 from          ≥0 from
  EXPECT_TRUE(has(0, false) && has(0, true));   // all              (3,7,0), (7,0,7)
  EXPECT_TRUE(has(1, false) && has(1, true));   // (0,0,0)          (3,7,0)
  EXPECT_TRUE(has(2, false) && has(2, true));   // (0,0,0)          (7,0,7)
  EXPECT_TRUE(has(3, false) && !has(3, true));  // (0,0,0)         —
  EXPECT_TRUE(has(4, false) && has(4, true));   // (0,0,0)          (3,7,0)
  EXPECT_TRUE(has(5, false) && has(5, true));   // (0,0,0)          (3,7,0)
  EXPECT_TRUE(has(6, false) && !has(6, true));  // (0,0,0)         —
  EXPECT_TRUE(has(7, false) && !has(7, true));  // (0,0,0)         —

  // Level 2 (step 4): only index 0 (centre 4) is near; the block reads the other level only.
  state.level = 2;
  block.writableAt(2, 0, 0, 0) = Voxel{};
  block.writableAt(2, 1, 0, 0).sdf_m = -1.0f;
  block.writableAt(2, 1, 0, 0).weight = 1.0f;
  refreshMeshSigns(block, &state);
  EXPECT_EQ(state.sign_bits, meshSignBit(0, false) | meshSignBit(2, false) | meshSignBit(4, false) |
                                 meshSignBit(6, false));
  // A negative too near 0 to keep its sign through the mesher's weighted sums counts as both.
  block.writableAt(2, 1, 0, 0).sdf_m = -1e-31f;
  refreshMeshSigns(block, &state);
  uint16_t both = 0;
  for (int region : {0, 2, 4, 6}) both |= meshSignBit(region, false) | meshSignBit(region, true);
  EXPECT_EQ(state.sign_bits, both);
}
