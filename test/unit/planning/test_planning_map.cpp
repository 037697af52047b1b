#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <thread>
#include <optional>
#include <tuple>

#include "TestSupport.h"
#include "stereo_fusion/Mapper.h"

namespace stereo_fusion {
namespace {

using test::renderFrame;
using test::vgaCamera;

MapperConfig planningConfig(int threads = 0) {
  MapperConfig c;
  c.voxel_size_m = 0.02;
  c.max_depth_m = 6.0;
  c.num_threads = threads;
  c.mesh_enabled = false;
  return c;
}

/// A box room 4 × 4 × 3 m (floor at z = 0) with a sphere of radius 0.4 m.
sim::AnalyticScene roomWithSphere() {
  sim::AnalyticScene scene;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0, 0, 1.5);
  scene.add(sim::makeRoom(T, Eigen::Vector3d(2.0, 2.0, 1.5)));
  scene.add(sim::makeSphere(Eigen::Vector3d(0.8, 0.3, 1.0), 0.4));
  return scene;
}

/// Cameras on a circle of radius 1.2 m at 1.2 m height, looking outwards.
std::vector<Eigen::Isometry3d> circlePoses(int n) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    const Eigen::Vector3d eye(-0.6 * std::cos(a), -0.6 * std::sin(a), 1.2);
    poses.push_back(sim::lookAt(eye, eye + Eigen::Vector3d(std::cos(a), std::sin(a), -0.15)));
  }
  return poses;
}

/// What the ESDF must read at free cell `p` against `occupied` (centres and cells), by brute
/// force: the nearest occupied centre (the smallest in (z, y, x) among equally near ones), moved
/// onto its surface by the site's centre_sdf, within [0, max].
double bruteForceDistance(const PlanningMap& planning, const Eigen::Vector3d& p,
                          const std::vector<CellIndex>& occupied) {
  const double max_m = planning.config().max_distance_m;
  const CellIndex* best = nullptr;
  double best_m = max_m;
  for (const CellIndex& o : occupied) {
    const double d = (planning.grid().centre(o) - p).norm();
    if (d < best_m ||
        (best && d == best_m && std::tie(o.z, o.y, o.x) < std::tie(best->z, best->y, best->x))) {
      best_m = d;
      best = &o;
    }
  }
  if (!best) return max_m;
  return std::clamp(best_m - planning.centreSdfM(*best), 0.0, max_m);
}

struct CellRecord {
  CellState state;
  double distance_m;
};
using CellKey = std::tuple<int, int, int>;

std::map<CellKey, CellRecord> cells(const PlanningMap& planning) {
  std::map<CellKey, CellRecord> out;
  planning.forEachKnownCell([&](const CellIndex& c, CellState s, double d) {
    out[{c.x, c.y, c.z}] = {s, d};
  });
  return out;
}

// One frame of a wall 3 m ahead: the space in front of it is free, the wall occupied, what lies
// behind it, beside the view and behind the camera unknown.
TEST(PlanningMap, OneFrameSeesFreeSpaceInFrontOfAWallAndNothingElse) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane(Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d(-1, 0, 0)));
  MapperConfig config = planningConfig();
  config.occupancy_min_weight = 1.0;  // one view is evidence here (PlanningEvidence.* test it)
  Mapper mapper(config);
  const Eigen::Isometry3d pose = sim::lookAt(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(3, 0, 1));
  ASSERT_TRUE(mapper.integrate(renderFrame(scene, vgaCamera(), pose)).accepted);
  mapper.updatePlanning();
  const PlanningMap& planning = *mapper.planning();
  EXPECT_EQ(planning.state({1.5, 0.0, 1.0}), CellState::kFree);
  EXPECT_EQ(planning.state({2.5, 0.3, 1.2}), CellState::kFree);
  EXPECT_EQ(planning.state({3.0, 0.0, 1.0}), CellState::kOccupied);
  EXPECT_EQ(planning.state({3.6, 0.0, 1.0}), CellState::kUnknown);   // behind the wall
  EXPECT_EQ(planning.state({1.0, 2.5, 1.0}), CellState::kUnknown);   // outside the view
  EXPECT_EQ(planning.state({-1.0, 0.0, 1.0}), CellState::kUnknown);  // behind the camera
  // Distances in front of the wall: to the nearest occupied cell centre, within a cell and a band.
  const EsdfSample s = planning.sample({2.0, 0.0, 1.0});
  EXPECT_EQ(s.state, CellState::kFree);
  EXPECT_NEAR(s.distance_m, 1.0, 0.2);
  EXPECT_TRUE(s.interpolated);
  EXPECT_NEAR(s.gradient.x(), -1.0, 0.2);  // the distance grows away from the wall (−x)
}

// The ESDF of a fused room with a sphere: every free cell's distance equals the brute-force
// distance to the nearest occupied cell within half a cell, and the analytic clearance within
// half a cell diagonal at the median (cell centres against surfaces anywhere in a cell).
TEST(PlanningMap, EsdfOfAFusedRoomMatchesBruteForceAndTheAnalyticScene) {
  const sim::AnalyticScene scene = roomWithSphere();
  Mapper mapper(planningConfig());
  for (const Eigen::Isometry3d& pose : circlePoses(24)) {  // a wall in ~4 views: evidence
    ASSERT_TRUE(mapper.integrate(renderFrame(scene, vgaCamera(), pose)).accepted);
    mapper.updatePlanning();
  }
  const PlanningMap& planning = *mapper.planning();
  const double cell_m = planning.config().cell_m, max_m = planning.config().max_distance_m;
  std::vector<CellIndex> occupied;
  std::vector<std::pair<Eigen::Vector3d, double>> free_cells;
  planning.forEachKnownCell([&](const CellIndex& c, CellState s, double d) {
    if (s == CellState::kOccupied) occupied.push_back(c);
    if (s == CellState::kFree) free_cells.emplace_back(planning.grid().centre(c), d);
  });
  ASSERT_GT(occupied.size(), 1000u);
  ASSERT_GT(free_cells.size(), 10000u);
  double worst_brute = 0.0;
  std::vector<double> analytic_errors, brute_errors;
  for (size_t i = 0; i < free_cells.size(); i += 7) {
    const auto& [p, d] = free_cells[i];
    const double brute = bruteForceDistance(planning, p, occupied);
    brute_errors.push_back(std::abs(d - brute));
    worst_brute = std::max(worst_brute, std::abs(d - brute));
    if (d < max_m - cell_m) analytic_errors.push_back(std::abs(d - scene.clearance(p)));
  }
  // Propagation over 26-neighbourhoods may keep a site a hair farther than the nearest centre;
  // its centre sdf then differs from the nearest's by up to two cells' worth (± a cell each).
  std::sort(brute_errors.begin(), brute_errors.end());
  EXPECT_LE(brute_errors[brute_errors.size() * 99 / 100], 0.5 * cell_m);
  EXPECT_LE(worst_brute, 2.0 * cell_m);
  ASSERT_GT(analytic_errors.size(), 1000u);
  std::sort(analytic_errors.begin(), analytic_errors.end());
  // Cells near the sphere's unseen far side read farther than the clearance: a share of them.
  EXPECT_LE(analytic_errors[analytic_errors.size() / 2], 0.5 * std::sqrt(3.0) * cell_m);
  // Surfaces fewer than two views agree on are no evidence (occupancy_min_weight): cells near
  // them read the next surface. Measured: p95 1.53 cells with 24 views.
  EXPECT_LE(analytic_errors[analytic_errors.size() * 95 / 100], 1.6 * cell_m);
}

// Updating the planning layer after every frame or once at the end, with one thread or two,
// gives the same cells, states and distances.
TEST(PlanningMap, IncrementalEqualsOneUpdateAndDoesNotDependOnThreads) {
  const sim::AnalyticScene scene = roomWithSphere();
  Mapper every_frame(planningConfig(1)), once(planningConfig(2));
  for (const Eigen::Isometry3d& pose : circlePoses(8)) {
    const StereoFrame frame = renderFrame(scene, vgaCamera(), pose, 0.1, 7);
    ASSERT_TRUE(every_frame.integrate(frame).accepted);
    every_frame.updatePlanning();
    ASSERT_TRUE(once.integrate(frame).accepted);
  }
  once.updatePlanning();
  const auto a = cells(*every_frame.planning()), b = cells(*once.planning());
  ASSERT_EQ(a.size(), b.size());
  size_t differing = 0;
  for (const auto& [key, record] : a) {
    const auto it = b.find(key);
    ASSERT_TRUE(it != b.end());
    differing += record.state != it->second.state || record.distance_m != it->second.distance_m;
  }
  EXPECT_EQ(differing, 0u);
}

// An update in two halves, as the node runs it (the second without the map lock): frames fused
// between the halves keep their free space, and their drops of far blocks, for the update's
// end. The layer then equals the one of updating before those frames — with the second half
// after them on the same thread, or on another thread beside them.
TEST(PlanningMap, FramesFusedWhileAnUpdateFinishesGiveTheLayerOfTheSerialOrder) {
  const sim::AnalyticScene scene = roomWithSphere();
  const std::vector<Eigen::Isometry3d> poses = circlePoses(8);
  auto frame = [&](int i) { return renderFrame(scene, vgaCamera(), poses[i], 0.1, 7 + i); };
  MapperConfig config = planningConfig();
  config.max_depth_m = 3.0;
  config.max_distance_from_camera_m = 3.0;  // each frame also drops the room's far corners
  Mapper serial(config), after(config), beside(config);
  for (int i = 0; i < 4; ++i)
    for (Mapper* m : {&serial, &after, &beside}) ASSERT_TRUE(m->integrate(frame(i)).accepted);
  serial.updatePlanning();
  // In front of frame 5's camera, outside the views of frames 0-3.
  const Eigen::Vector3d seen_later(-0.7, -0.7, 1.1);
  ASSERT_EQ(serial.planning()->state(seen_later), CellState::kUnknown);
  for (int i = 4; i < 8; ++i) ASSERT_TRUE(serial.integrate(frame(i)).accepted);
  serial.updatePlanning();
  ASSERT_EQ(serial.planning()->state(seen_later), CellState::kFree);

  std::optional<PlanningMap::PendingUpdate> pending = after.beginPlanningUpdate();
  ASSERT_TRUE(pending);
  for (int i = 4; i < 8; ++i) ASSERT_TRUE(after.integrate(frame(i)).accepted);
  EXPECT_EQ(after.planning()->writesKeptForUpdate(), 8u) << "each frame's free space and drop";
  EXPECT_EQ(after.planning()->state(seen_later), CellState::kUnknown) << "not added yet";
  after.finishPlanningUpdate(std::move(*pending));
  EXPECT_EQ(after.planning()->state(seen_later), CellState::kFree) << "added at the end";
  after.updatePlanning();

  pending = beside.beginPlanningUpdate();
  ASSERT_TRUE(pending);
  ASSERT_TRUE(beside.integrate(frame(4)).accepted);  // kept whatever the timing below
  std::thread finisher([&] { beside.finishPlanningUpdate(std::move(*pending)); });
  for (int i = 5; i < 8; ++i) EXPECT_TRUE(beside.integrate(frame(i)).accepted);
  finisher.join();
  EXPECT_GE(beside.planning()->writesKeptForUpdate(), 2u);
  beside.updatePlanning();

  const auto expected = cells(*serial.planning());
  for (const Mapper* m : {&after, &beside}) {
    const auto got = cells(*m->planning());
    ASSERT_EQ(got.size(), expected.size());
    size_t differing = 0;
    for (const auto& [key, record] : expected) {
      const auto it = got.find(key);
      differing += it == got.end() || it->second.state != record.state ||
                   it->second.distance_m != record.distance_m;
    }
    EXPECT_EQ(differing, 0u);
    EXPECT_TRUE(m->planning()->seenFree() == serial.planning()->seenFree());
    EXPECT_EQ(m->planning()->blockCount(), serial.planning()->blockCount());  // read unlocked
    EXPECT_EQ(m->planning()->esdfBytes(), serial.planning()->esdfBytes());
  }
}

// A clear makes its region unknown (free cells and surfaces alike); a later frame fills it again.
TEST(PlanningMap, ClearMakesTheRegionUnknownUntilSeenAgain) {
  const sim::AnalyticScene scene = roomWithSphere();
  MapperConfig config = planningConfig();
  config.occupancy_min_weight = 1.0;  // one view is evidence: "seen again" is one frame
  Mapper mapper(config);
  const auto poses = circlePoses(8);
  for (const Eigen::Isometry3d& pose : poses)
    ASSERT_TRUE(mapper.integrate(renderFrame(scene, vgaCamera(), pose)).accepted);
  mapper.updatePlanning();
  const PlanningMap& planning = *mapper.planning();
  const Eigen::Vector3d free_point(0.0, 0.0, 1.2), wall_point(-2.03, 0.0, 1.0);
  ASSERT_EQ(planning.state(free_point), CellState::kFree);
  ASSERT_EQ(planning.state(wall_point), CellState::kOccupied);
  ASSERT_TRUE(mapper.clearRegion(MapRegion::box({-0.3, -0.3, 0.9}, {0.3, 0.3, 1.5})).accepted);
  ASSERT_TRUE(mapper.clearRegion(MapRegion::box({-2.3, -0.3, 0.7}, {-1.7, 0.3, 1.3})).accepted);
  mapper.updatePlanning();
  EXPECT_EQ(planning.state(free_point), CellState::kUnknown);
  EXPECT_EQ(planning.state(wall_point), CellState::kUnknown);
  EXPECT_TRUE(std::isnan(planning.sample(free_point).distance_m));
  // The wall's cells are gone from the distance field too: a free cell near it now reads farther.
  const EsdfSample near_wall = planning.sample({-1.4, 0.0, 1.0});
  EXPECT_GT(near_wall.distance_m, 0.5);
  ASSERT_TRUE(mapper.integrate(renderFrame(scene, vgaCamera(), poses[4])).accepted);
  mapper.updatePlanning();
  EXPECT_EQ(planning.state(wall_point), CellState::kOccupied);
  EXPECT_LE(planning.sample({-1.4, 0.0, 1.0}).distance_m, 0.65);
}

// A clear leaves a hole of whole planning blocks between a wall and the free space in front of
// it (x −1.92..−1.28 m, the wall at −2 m). The cells across it still read their distance to
// the wall through the transit blocks, after the update and after a rebuild from scratch, and
// the two agree; without them the cells in the hole's shadow would read the wall around it.
TEST(PlanningMap, DistancesCrossAHoleTheClearLeft) {
  const sim::AnalyticScene scene = roomWithSphere();
  Mapper mapper(planningConfig());
  for (const Eigen::Isometry3d& pose : circlePoses(8))
    ASSERT_TRUE(mapper.integrate(renderFrame(scene, vgaCamera(), pose)).accepted);
  mapper.updatePlanning();
  const PlanningMap& planning = *mapper.planning();
  ASSERT_DOUBLE_EQ(planning.grid().blockM(), 0.64);
  const Eigen::Vector3d hole_min(-1.92, -0.64, 1.28), hole_max(-1.28, 0.64, 1.92);
  ASSERT_EQ(planning.state(0.5 * (hole_min + hole_max)), CellState::kFree);
  ASSERT_TRUE(mapper.clearRegion(MapRegion::box(hole_min, hole_max)).accepted);
  mapper.updatePlanning();
  ASSERT_EQ(planning.state(0.5 * (hole_min + hole_max)), CellState::kUnknown);

  auto check = [&](const char* when) {
    std::vector<CellIndex> occupied;
    std::vector<std::pair<Eigen::Vector3d, double>> shadow;  // free cells behind the hole
    planning.forEachKnownCell([&](const CellIndex& c, CellState s, double d) {
      const Eigen::Vector3d p = planning.grid().centre(c);
      if (s == CellState::kOccupied) occupied.push_back(c);
      if (s == CellState::kFree && p.x() > -1.28 && p.x() < -0.4 && std::abs(p.y()) < 0.64 &&
          p.z() > 1.28 && p.z() < 1.92)
        shadow.emplace_back(p, d);
    });
    ASSERT_GT(shadow.size(), 500u) << when;
    double worst = 0.0;
    for (const auto& [p, d] : shadow) {
      worst = std::max(worst, std::abs(d - bruteForceDistance(planning, p, occupied)));
    }
    EXPECT_LE(worst, 0.5 * planning.grid().cell_m) << when;
  };
  check("after the update");
  const auto incremental = cells(planning);
  mapper.rebuildPlanning();
  check("after a rebuild");
  const auto rebuilt = cells(planning);
  ASSERT_EQ(incremental.size(), rebuilt.size());
  size_t differing = 0;
  for (const auto& [key, record] : incremental) {
    const CellRecord& other = rebuilt.at(key);
    differing += record.state != other.state || record.distance_m != other.distance_m;
  }
  EXPECT_EQ(differing, 0u);
}

// The transit rule runs again when a block's cells spread, not only when it first holds a
// kind. An occupied cell (0, 4, 4) and, three blocks on, a free cell at x = 31: 31 cells apart,
// beyond the 25-cell reach, so nothing lies between them. Then x = 24 of that block is seen free:
// 24 cells from the obstacle, across two absent blocks, which the grown box now calls for —
// the cell reads 24 · 8 cm = 1.92 m, not the 2 m of "no site", and a rebuild agrees.
TEST(PlanningMap, AFreeBoxThatGrowsWithinReachGetsItsTransitBlocks) {
  PlanningConfig config;  // 8 cm cells of 4 voxels of 2 cm, 2 m
  ThreadPool pool(1);
  PlanningMap planning(config, &pool);
  BlockOctree octree(0.16);
  auto tsdf = std::make_unique<VoxelBlock>();
  tsdf->key = {0, 2, 2};  // voxels 0–7, 16–23, 16–23: planning cells x 0–1, y 4–5, z 4–5
  Voxel& behind = tsdf->writableAt(0, 0, 0, 0);
  behind.sdf_m = 0.01f;  // just behind a surface: occupied
  behind.weight = 2.0f;  // occupancy_min_weight: evidence
  octree.insert(std::move(tsdf));
  planning.update(octree, {{0, 2, 2}}, {});
  auto seeFree = [&](int x) {
    PlanningBlock::Bits bits{};
    PlanningBlock::set(&bits, PlanningBlock::index(x - 24, 4, 4), true);
    planning.addSeenFree({{BlockKey{3, 0, 0}, bits}});
    planning.update(octree, {}, {});
  };
  const Eigen::Vector3d far_cell(31.5 * 0.08, 4.5 * 0.08, 4.5 * 0.08);
  const Eigen::Vector3d near_cell(24.5 * 0.08, 4.5 * 0.08, 4.5 * 0.08);
  seeFree(31);
  ASSERT_EQ(planning.state({0.04, 0.36, 0.36}), CellState::kOccupied);
  EXPECT_EQ(planning.blockCount(), 2u);
  EXPECT_DOUBLE_EQ(planning.sample(far_cell).distance_m, 2.0);  // 31 cells: beyond the max
  seeFree(24);
  EXPECT_EQ(planning.blockCount(), 4u);  // (1, 0, 0) and (2, 0, 0) between them
  EXPECT_NEAR(planning.sample(near_cell).distance_m, 1.92, 1e-9);
  planning.rebuild(octree);
  EXPECT_EQ(planning.blockCount(), 4u);
  EXPECT_NEAR(planning.sample(near_cell).distance_m, 1.92, 1e-9);
}

// A box that was there and has gone: carving turns its cells free, and the distance field follows.
TEST(PlanningMap, AnObjectThatLeftBecomesFree) {
  sim::AnalyticScene with_box;
  with_box.add(sim::makePlane(Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d(-1, 0, 0)));
  Eigen::Isometry3d T_box = Eigen::Isometry3d::Identity();
  T_box.translation() = Eigen::Vector3d(1.5, 0.0, 1.0);
  with_box.add(sim::makeBox(T_box, Eigen::Vector3d(0.2, 0.2, 0.2)));
  sim::AnalyticScene without_box;
  without_box.add(sim::makePlane(Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d(-1, 0, 0)));
  Mapper mapper(planningConfig());
  const Eigen::Isometry3d pose = sim::lookAt(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(3, 0, 1));
  for (int i = 0; i < 5; ++i)
    ASSERT_TRUE(mapper.integrate(renderFrame(with_box, vgaCamera(), pose, 0.0)).accepted);
  mapper.updatePlanning();
  const PlanningMap& planning = *mapper.planning();
  ASSERT_EQ(planning.state({1.3, 0.0, 1.0}), CellState::kOccupied);
  for (int i = 0; i < 30; ++i) {
    StereoFrame frame = renderFrame(without_box, vgaCamera(), pose, 0.0);
    frame.timestamp_s = 1.0 + i;
    ASSERT_TRUE(mapper.integrate(frame).accepted);
  }
  mapper.updatePlanning();
  EXPECT_EQ(planning.state({1.3, 0.0, 1.0}), CellState::kFree);
  EXPECT_GT(planning.sample({1.0, 0.0, 1.0}).distance_m, 1.5);
}

}  // namespace
}  // namespace stereo_fusion

namespace stereo_fusion {
namespace {

std::map<std::tuple<int, int, int>, std::pair<CellState, double>> cellMap(
    const PlanningMap& planning) {
  std::map<std::tuple<int, int, int>, std::pair<CellState, double>> out;
  planning.forEachKnownCell([&](const CellIndex& c, CellState s, double d) {
    out[{c.x, c.y, c.z}] = {s, d};
  });
  return out;
}

// The map file keeps the seen-free space: a loaded map answers every cell as the saved one did.
// A version-2 file (no seen-free section) loads with only the TSDF's cells known.
/// A wall 3 m ahead seen by one frame from (0, 0, 1), the planning layer brought up to date.
void fuseOneViewOfAWall(Mapper* mapper) {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane(Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d(-1, 0, 0)));
  const Eigen::Isometry3d pose = sim::lookAt(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(3, 0, 1));
  ASSERT_TRUE(mapper->integrate(test::renderFrame(scene, test::vgaCamera(), pose)).accepted);
  mapper->updatePlanning();
}

TEST(PlanningMapFile, SavedAndLoadedLayerIsTheSameAndOlderFilesLoadWithFreeSpaceUnknown) {
  MapperConfig config;
  config.mesh_enabled = false;
  config.occupancy_min_weight = 1.0;  // one view is evidence: the wall is an obstacle
  Mapper original(config);
  ASSERT_NO_FATAL_FAILURE(fuseOneViewOfAWall(&original));
  const auto saved_cells = cellMap(*original.planning());
  ASSERT_EQ(original.planning()->state({1.0, 0.0, 1.0}),
            CellState::kFree);  // seen free, far from the band

  std::vector<uint8_t> bytes = original.encodeMap();
  sealMapFile(&bytes);
  BlockOctree octree(config.blockSizeM());
  MapFileInfo info;
  std::string error;
  ASSERT_TRUE(decodeMapFile(bytes.data(), bytes.size(), config, &octree, &info, &error)) << error;
  EXPECT_EQ(info.free_space.cell_m, original.planning()->grid().cell_m);
  EXPECT_EQ(info.free_space.blocks, original.planning()->seenFree());
  Mapper loaded(config);
  loaded.adoptMap(&octree, info);
  EXPECT_TRUE(cellMap(*loaded.planning()) == saved_cells);

  // The same file as version 2: drop the section, fix the version and the payload size.
  std::vector<uint8_t> v2(bytes.begin(), bytes.end() - (16 + info.free_space.blocks.size() *
                                                                 kMapFileFreeSpaceRecordBytes));
  v2[8] = 2;
  const uint64_t payload = v2.size() - kMapFileHeaderBytes;
  for (int b = 0; b < 8; ++b) v2[64 + b] = static_cast<uint8_t>(payload >> (8 * b));
  sealMapFile(&v2);
  BlockOctree octree2(config.blockSizeM());
  ASSERT_TRUE(decodeMapFile(v2.data(), v2.size(), config, &octree2, &info, &error)) << error;
  EXPECT_EQ(info.free_space.cell_m, 0.0);
  Mapper older(config);
  older.adoptMap(&octree2, info);
  EXPECT_EQ(older.planning()->state({1.0, 0.0, 1.0}), CellState::kUnknown);
  EXPECT_EQ(older.planning()->state({3.0, 0.0, 1.0}), CellState::kOccupied);
  EXPECT_LT(cellMap(*older.planning()).size(), saved_cells.size());
}

// A crafted file: a seen-free record's key set beyond the planning grid (still in sort order,
// checksums sealed again) is refused with the record named, not loaded as a block 2^26 blocks
// out that the occupancy grid would then span. The last key in range loads.
TEST(PlanningMapFile, SeenFreeKeysBeyondThePlanningGridAreRefused) {
  MapperConfig config;
  config.mesh_enabled = false;
  Mapper original(config);
  ASSERT_NO_FATAL_FAILURE(fuseOneViewOfAWall(&original));
  const size_t records = original.planning()->seenFree().size();
  ASSERT_GT(records, 0u);
  std::vector<uint8_t> bytes = original.encodeMap();
  // The seen-free section ends the payload; its last record's key x is its first 4 bytes.
  const size_t last_x = bytes.size() - kMapFileFreeSpaceRecordBytes;
  auto withKeyX = [&](int32_t x) {
    std::vector<uint8_t> crafted = bytes;
    for (int b = 0; b < 4; ++b)
      crafted[last_x + b] = static_cast<uint8_t>(static_cast<uint32_t>(x) >> (8 * b));
    sealMapFile(&crafted);
    return crafted;
  };
  const int32_t limit = kPlanningCellLimit / PlanningBlock::kSide;  // 2^25
  for (const int32_t x : {int32_t{1} << 26, limit, limit - 1}) {
    const std::vector<uint8_t> crafted = withKeyX(x);
    BlockOctree octree(config.blockSizeM());
    MapFileInfo info;
    std::string error;
    const bool decoded =
        decodeMapFile(crafted.data(), crafted.size(), config, &octree, &info, &error);
    if (x >= limit) {
      EXPECT_FALSE(decoded) << x;
      EXPECT_NE(
          error.find("seen-free block " + std::to_string(records - 1) + " (" + std::to_string(x)),
          std::string::npos)
          << error;
      EXPECT_NE(error.find("beyond the planning grid's range"), std::string::npos) << error;
    } else {
      EXPECT_TRUE(decoded) << error;
    }
  }
}

}  // namespace
}  // namespace stereo_fusion
