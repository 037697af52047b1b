// A loop closure on a paged map (max_map_memory_mb): the re-fusion pages into a store of its
// own, and the swapped-in map's outputs equal the uncapped session's byte for byte.
#include <gtest/gtest.h>

#include "SessionTestSupport.h"
#include "stereo_fusion/session/MappingSession.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

TEST(SessionPaging, ACorrectionOfAPagedMapEqualsTheUncappedOne) {
  SessionConfig keep;
  keep.loop_closure_max_frames = 100;
  keep.background_corrections = false;
  struct Run {
    std::vector<uint8_t> map_file;
    TriangleMesh mesh;
    std::vector<BlockKey> removed_on_swap;
    PagingStats paging;
  };
  auto run = [&](double cap_mb) {
    MapperConfig config = sessionTestConfig();
    config.max_map_memory_mb = cap_mb;
    MappingSession session(config, keep);
    Run r;
    session.setMapReplacedListener([&](const MapReplaced& replaced) {
      if (replaced.change == MapChange::kCorrected) r.removed_on_swap = replaced.removed;
    });
    for (int i = 0; i < kFrames; ++i)
      EXPECT_EQ(session.fuse(driftingFrame(i), session.arrive(), MeshTiming::kNow).reason,
                RejectReason::kNone);
    r.paging = session.read([](const Mapper& m) { return m.pagingStats(); });
    const std::optional<CorrectionReport> report = session.submitTrajectory(keyframes());
    EXPECT_TRUE(report && report->outcome == TrajectoryOutcome::kApplied);
    session.read([&](const Mapper& m) {
      r.map_file = m.encodeMap();
      r.mesh = m.extractMesh();
    });
    return r;
  };
  const Run uncapped = run(0.0);
  double map_mb = 0.0;
  {
    Mapper m(sessionTestConfig());
    for (int i = 0; i < kFrames; ++i) m.integrate(driftingFrame(i));
    map_mb = m.mapMemoryBytes() / (1024.0 * 1024.0);
  }
  const Run capped = run(0.4 * map_mb);
  EXPECT_GT(capped.paging.blocks_paged_out, 0u) << "the cap must page the live map";
  EXPECT_TRUE(capped.map_file == uncapped.map_file);
  EXPECT_EQ(capped.mesh.positions, uncapped.mesh.positions);
  EXPECT_EQ(capped.mesh.triangles, uncapped.mesh.triangles);
  EXPECT_EQ(capped.removed_on_swap, uncapped.removed_on_swap)
      << "submeshes the correction removed, paged-out ones included";
}
