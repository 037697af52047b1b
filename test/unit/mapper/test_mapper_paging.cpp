// Paging (max_map_memory_mb): a map capped below its size pages blocks out to the block store
// and back, and every output — the mesh, the map file, the ESDF and the occupancy grid — is
// byte-identical to the uncapped map's, over random caps, trajectories and operations.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

#include "MeshTestSupport.h"
#include "PagingTestSupport.h"
#include "QuickMode.h"
#include "stereo_fusion/io/PlanningExport.h"
#include "stereo_fusion/planning/OccupancyGrid2D.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;
namespace fs = std::filesystem;

TEST(MapperPaging, AnyCapGivesTheUncappedOutputsByteForByte) {
  const int runs = quickMode() ? 2 : 5;
  Scratch scratch;
  for (int run = 0; run < runs; ++run) {
    std::mt19937 rng(100 + run);
    const int frames = quickMode() ? 24 : 40;
    const std::vector<Eigen::Isometry3d> poses = walk(&rng, frames);
    // The operations a long session has: meshing at a cadence, eviction by distance, a clear.
    const int mesh_every = std::uniform_int_distribution<int>(1, 4)(rng);
    const int plan_every = std::uniform_int_distribution<int>(1, 6)(rng);
    MapperConfig config = hallConfig();
    if (run % 2 == 1) config.max_distance_from_camera_m = 5.0;
    const int clear_at = std::uniform_int_distribution<int>(frames / 2, frames - 2)(rng);
    HallSession session;
    session.poses = poses;
    session.seed = run;
    session.mesh_every = mesh_every;
    session.plan_every = plan_every;
    session.clear_at = clear_at;

    auto fuse = [&](Mapper* mapper, size_t* peak_bytes) {
      for (int f = 0; f < frames; ++f) {
        session.frame(mapper, f);
        *peak_bytes = std::max(*peak_bytes, mapper->mapMemoryBytes());
      }
    };
    Mapper uncapped(config);
    size_t uncapped_peak = 0;
    fuse(&uncapped, &uncapped_peak);
    const Outputs expected = outputsOf(&uncapped, scratch.path);
    ASSERT_GT(expected.mesh.triangles.size(), 1000u);

    const double share = std::uniform_real_distribution<double>(0.25, 0.6)(rng);
    config.max_map_memory_mb = share * uncapped_peak / (1024.0 * 1024.0);
    config.map_store_path = scratch.path.string();
    Mapper capped(config);
    size_t capped_peak = 0;
    fuse(&capped, &capped_peak);
    const std::string what =
        "run " + std::to_string(run) + ", cap " + std::to_string(share) + " of the uncapped peak";
    EXPECT_GT(capped.pagingStats().blocks_paged_out, 0u) << what;
    EXPECT_GT(capped.pagingStats().blocks_paged_in, 0u) << what << ": the walk back pages in";
    EXPECT_EQ(capped.pagingStats().pages_unreadable, 0u) << capped.pagingStats().error;
    EXPECT_LT(capped_peak, uncapped_peak) << what;
    expectSameOutputs(outputsOf(&capped, scratch.path), expected, what);
    // Nothing pending: the map fits its cap.
    EXPECT_LE(capped.mapMemoryBytes(), config.max_map_memory_mb * 1024 * 1024) << what;
    EXPECT_GT(capped.pagedOutBlocks(), 0u) << what;
  }
}

TEST(MapperPaging, AResetOrALoadedMapStartsAfreshAndRebuildsSeeEveryBlock) {
  const sim::AnalyticScene scene = hall();
  Scratch scratch;
  std::mt19937 rng(7);
  const std::vector<Eigen::Isometry3d> poses = walk(&rng, 30);
  MapperConfig config = hallConfig();
  Mapper uncapped(config);
  for (int f = 0; f < 30; ++f) uncapped.integrate(renderFrame(scene, qvgaCamera(), poses[f]));
  config.max_map_memory_mb = 0.4 * uncapped.mapMemoryBytes() / (1024.0 * 1024.0);
  config.map_store_path = scratch.path.string();
  Mapper capped(config);
  for (int f = 0; f < 30; ++f) capped.integrate(renderFrame(scene, qvgaCamera(), poses[f]));
  ASSERT_GT(capped.pagedOutBlocks(), 0u);
  // A rebuild covers the paged-out blocks too.
  EXPECT_EQ(capped.rebuildMesh().changed, uncapped.rebuildMesh().changed);
  // Saved capped, loaded uncapped: the same map; loaded capped: the same file again.
  const fs::path file = scratch.path / "map.sfmap";
  std::string error;
  ASSERT_TRUE(capped.saveMap(file.string(), &error)) << error;
  // Streamed block by block, the file is the one the uncapped map's bytes make.
  std::vector<uint8_t> expected = uncapped.encodeMap();
  sealMapFile(&expected);
  const std::string saved = fileBytes(file);
  EXPECT_TRUE(saved == std::string(expected.begin(), expected.end()));
  Mapper reloaded(config);
  ASSERT_TRUE(reloaded.loadMap(file.string(), nullptr, &error)) << error;
  EXPECT_TRUE(reloaded.encodeMap() == uncapped.encodeMap());
  capped.reset();
  EXPECT_EQ(capped.pagedOutBlocks(), 0u);
  EXPECT_EQ(capped.tsdf().blockCount(), 0u);
  EXPECT_TRUE(capped.extractMesh().triangles.empty());
}

TEST(MapperPaging, AFullDiskStopsPagingAndKeepsTheMapWhole) {
  const sim::AnalyticScene scene = hall();
  Scratch scratch;
  std::mt19937 rng(11);
  const std::vector<Eigen::Isometry3d> poses = walk(&rng, 30);
  MapperConfig config = hallConfig();
  Mapper uncapped(config);
  for (int f = 0; f < 30; ++f) uncapped.integrate(renderFrame(scene, qvgaCamera(), poses[f]));
  config.max_map_memory_mb = 0.3 * uncapped.mapMemoryBytes() / (1024.0 * 1024.0);
  config.map_store_path = scratch.path.string();
  Mapper capped(config);
  // The store's files may not grow beyond 64 KiB: its first page-out fails as on a full disk.
  struct rlimit old_limit {};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit small = old_limit;
  small.rlim_cur = 64 * 1024;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  for (int f = 0; f < 30; ++f) capped.integrate(renderFrame(scene, qvgaCamera(), poses[f]));
  capped.flushPaging();  // the writer's last batch, refused too
  setrlimit(RLIMIT_FSIZE, &old_limit);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_TRUE(capped.pagingStats().stopped);
  EXPECT_NE(capped.pagingStats().error.find("paging stopped"), std::string::npos)
      << capped.pagingStats().error;
  EXPECT_EQ(capped.pagedOutBlocks(), 0u) << "the store kept nothing";
  Outputs a = outputsOf(&capped, scratch.path), b = outputsOf(&uncapped, scratch.path);
  expectSameOutputs(a, b, "after a failed page-out");
}

TEST(MapperPaging, ABlockBackUnchangedLeavesWithoutAWriteAndAChangedOneIsWritten) {
  const sim::AnalyticScene scene = hall();
  Scratch scratch;
  std::mt19937 rng(13);
  const std::vector<Eigen::Isometry3d> poses = walk(&rng, 30);
  MapperConfig config = hallConfig();
  Mapper uncapped(config);
  for (int f = 0; f < 30; ++f) uncapped.integrate(renderFrame(scene, qvgaCamera(), poses[f]));
  config.max_map_memory_mb = 0.4 * uncapped.mapMemoryBytes() / (1024.0 * 1024.0);
  config.map_store_path = scratch.path.string();
  Mapper capped(config);
  for (int f = 0; f < 30; ++f) capped.integrate(renderFrame(scene, qvgaCamera(), poses[f]));
  const size_t paged = capped.pagedOutBlocks();
  ASSERT_GT(paged, 0u);

  // A planning rebuild brings every block back and changes none: the next page-out, which
  // takes the blocks that had left first (they are the least recently used still), keeps
  // their pages in the store instead of writing them again.
  capped.updateMesh();
  capped.rebuildPlanning();
  ASSERT_EQ(capped.pagedOutBlocks(), 0u);
  const PagingStats before = capped.pagingStats();
  capped.updateMesh();
  const PagingStats after = capped.pagingStats();
  const uint64_t left = after.blocks_paged_out - before.blocks_paged_out;
  const uint64_t kept = after.pages_kept - before.pages_kept;
  ASSERT_GT(left, paged / 2);
  EXPECT_GT(kept, left / 2);
  EXPECT_LE(kept, left);

  // A clear changes the blocks it reaches: those come back, change, and are written when they
  // leave again (a kept stale page would bring the cleared voxels back below).
  const MapRegion region = MapRegion::box({0.0, 1.5, 0.0}, {2.5, 3.2, 1.0});
  ASSERT_TRUE(capped.clearRegion(region, MeshTiming::kDeferred).accepted);
  ASSERT_TRUE(uncapped.clearRegion(region, MeshTiming::kDeferred).accepted);
  capped.rebuildPlanning();
  capped.updateMesh();
  EXPECT_GT(capped.pagingStats().bytes_written, after.bytes_written);
  for (int f = 0; f < 6; ++f) {
    capped.integrate(renderFrame(scene, qvgaCamera(), poses[f]));
    uncapped.integrate(renderFrame(scene, qvgaCamera(), poses[f]));
  }
  EXPECT_GT(capped.pagedOutBlocks(), 0u);
  expectSameOutputs(outputsOf(&capped, scratch.path), outputsOf(&uncapped, scratch.path),
                    "after blocks came back unchanged and changed");
}

namespace {
/// A corridor 12 m long walked along at 1.5 m from its wall, 40 frames: one view reaches a
/// small part of the map.
struct Corridor {
  sim::AnalyticScene scene;
  std::vector<Eigen::Isometry3d> poses;
  Corridor() {
    scene.add(sim::makePlane({0, 0, 0}, {0, 0, 1}), {170, 160, 140});
    scene.add(sim::makePlane({0, 1.5, 0}, {0, -1, 0}), {120, 140, 190});
    for (int k = 0; k < 13; ++k)
      scene.add(sim::makeSphere({1.0 * k, 1.2, 0.4}, 0.25), {200.0, 80.0 + 10 * k, 60.0});
    for (int f = 0; f < 40; ++f) {
      const Eigen::Vector3d eye(0.3 * f, 0.0, 1.0);
      poses.push_back(
          sim::lookAt(eye, eye + Eigen::Vector3d(0.0, 1.5, -0.4), Eigen::Vector3d::UnitZ()));
    }
  }
  StereoFrame frame(size_t f) const { return renderFrame(scene, qvgaCamera(), poses[f]); }
  void walk(Mapper* mapper) const {
    for (size_t f = 0; f < poses.size(); ++f) mapper->integrate(frame(f));
  }
};
}  // namespace

TEST(MapperPaging, WhatAFrameReachedStaysForTheNextFrame) {
  // A camera that holds still brings back what its view reaches once: the page-out after the
  // frame takes other blocks, not those the frame reached and left unchanged. One view of the
  // corridor fits the cap.
  const Corridor corridor;
  Scratch scratch;
  MapperConfig config = hallConfig();
  Mapper uncapped(config);
  corridor.walk(&uncapped);
  config.max_map_memory_mb = 0.4 * uncapped.mapMemoryBytes() / (1024.0 * 1024.0);
  config.map_store_path = scratch.path.string();
  Mapper capped(config);
  corridor.walk(&capped);
  for (const int f : {3, 20, 8}) {  // back along the corridor, where the map was paged out
    const StereoFrame frame = corridor.frame(f);
    const IntegrationResult first = capped.integrate(frame);
    const IntegrationResult again = capped.integrate(frame);
    EXPECT_GT(first.blocks_paged_in, 0u) << "frame " << f;
    EXPECT_GT(first.blocks_paged_out, 0u) << "frame " << f;
    EXPECT_EQ(again.blocks_paged_in, 0u) << "frame " << f << " seen again";
  }
}

TEST(MapperPaging, AFrameThatBringsBlocksBackMakesRoomBeforeItFuses) {
  // Back at the start of a corridor, a view brings back most of a cap's worth of blocks: the
  // blocks it does not reach leave before it fuses, so the map stays within the cap through
  // the frame, not only after it. Paging out after the frame alone held the cap's resident
  // blocks and the view's together.
  const Corridor corridor;
  Scratch scratch;
  MapperConfig config = hallConfig();
  Mapper uncapped(config);
  corridor.walk(&uncapped);
  config.max_map_memory_mb = 0.3 * uncapped.mapMemoryBytes() / (1024.0 * 1024.0);
  config.map_store_path = scratch.path.string();
  const size_t cap = static_cast<size_t>(config.max_map_memory_mb * 1024.0 * 1024.0);
  Mapper capped(config);
  corridor.walk(&capped);
  // The corridor's start, paged out since.
  const IntegrationResult back = capped.integrate(corridor.frame(2));
  ASSERT_GT(back.blocks_paged_in * (capped.mapMemoryBytes() / capped.tsdf().blockCount()), cap / 4)
      << "the view brings back a quarter of the cap at least";
  EXPECT_LE(back.map_memory_bytes, cap);
  EXPECT_LE(capped.pagingStats().map_memory_peak_bytes,
            uncapped.mapMemoryBytes())  // recorded, and a peak, not the map now
      << "peak";
  EXPECT_GE(capped.pagingStats().map_memory_peak_bytes, capped.mapMemoryBytes());
}
