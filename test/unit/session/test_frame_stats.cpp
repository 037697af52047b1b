// FrameStats: the one translation of a fused frame's IntegrationResult (and the passes after it)
// into the statistics of /diagnostics and stats.json.
#include <gtest/gtest.h>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/session/FrameStats.h"

using namespace stereo_fusion;

namespace {
IntegrationResult resultWithFigures() {
  IntegrationResult r;
  r.accepted = true;
  r.lookup_ms = 1.0;
  r.fusion_ms = 2.0;
  r.carve_ms = 4.0;
  r.contradiction_ms = 0.5;
  r.free_space_ms = 0.25;
  r.free_space.nodes_visited = 11;
  r.mesh.meshing_ms = 8.0;
  r.texture.texture_ms = 16.0;
  r.lookup.valid_points = 100;
  r.lookup.octree_searches = 7;
  r.lookup.blocks_queued = 5;
  r.lookup.box_blocks = 9;
  r.fusion.blocks_updated = 4;
  r.fusion.voxels_updated = 300;
  r.fusion.blocks_created = 2;
  r.fusion.blocks_not_created = 1;
  r.carve.blocks_carved = 3;
  r.carve.voxels_carved = 30;
  r.rejected.speckle_pixels = 6;
  r.rejected.edge_pixels = 12;
  r.contradiction.pixels_rejected = 13;
  return r;
}
}  // namespace

TEST(FrameStats, EveryFigureOfTheResultLandsInItsField) {
  IntegrationResult r = resultWithFigures();
  FrameStats s = frameStats(r, true);
  const StageTimings& t = s.timings;
  EXPECT_EQ(t.lookup_ms, 1.0);
  EXPECT_EQ(t.fusion_ms, 2.0);
  EXPECT_EQ(t.carve_ms, 4.0);
  EXPECT_EQ(t.meshing_ms, 8.0);
  EXPECT_EQ(t.texture_ms, 16.0);
  EXPECT_EQ(t.contradiction_ms, 0.5);
  EXPECT_EQ(t.free_space_ms, 0.25);
  EXPECT_EQ(t.free_space_nodes, 11.0);
  EXPECT_TRUE(t.meshed);
  EXPECT_EQ(t.total_ms, 0.0) << "the caller times the frame";
  EXPECT_EQ(t.mapUpdateMs(), 7.0);
  EXPECT_EQ(t.stagesMs(), 31.0);
  EXPECT_FALSE(s.mesh_pass_ran) << "the pass changed and visited nothing";
  const StageWork& w = s.work;
  EXPECT_EQ(w.valid_points, 100.0);
  EXPECT_EQ(w.octree_searches, 7.0);
  EXPECT_EQ(w.blocks_queued, 5.0);
  EXPECT_EQ(w.blocks_updated, 4.0);
  EXPECT_EQ(w.voxels_updated, 300.0);
  EXPECT_EQ(w.blocks_meshed, 0.0);
  EXPECT_EQ(w.submeshes_changed, 0.0);
  EXPECT_EQ(w.blocks_created, 2.0);
  EXPECT_EQ(w.blocks_not_created, 1.0);
  EXPECT_EQ(w.blocks_carved, 3.0);
  EXPECT_EQ(w.voxels_carved, 30.0);
  EXPECT_EQ(w.lookup_box_blocks, 9.0);

  r.mesh.changed = {BlockKey{0, 0, 0}, BlockKey{1, 0, 0}};
  r.mesh.blocks_meshed = 5;
  s = frameStats(r, false);
  EXPECT_FALSE(s.timings.meshed);
  EXPECT_TRUE(s.mesh_pass_ran);
  EXPECT_EQ(s.work.blocks_meshed, 5.0);
  EXPECT_EQ(s.work.submeshes_changed, 2.0);

  MeshPass mesh;
  mesh.mesh.meshing_ms = 3.0;
  mesh.texture.texture_ms = 1.5;
  s.timings.addMeshPass(mesh);
  EXPECT_TRUE(s.timings.meshed);
  EXPECT_EQ(s.timings.meshing_ms, 3.0);
  EXPECT_EQ(s.timings.texture_ms, 1.5);

  PlanningPass plan;
  plan.esdf_ms = 9.0;
  plan.stats.read_ms = 1.0;
  plan.stats.propagate_ms = 2.0;
  plan.stats.transit_ms = 3.0;
  plan.stats.transit_allocated = 4;
  plan.stats.tsdf_blocks = 5;
  plan.stats.esdf.cells_flipped = 6;
  plan.stats.esdf.cells_raised = 7;
  plan.stats.esdf.cells_lowered = 8;
  s.timings.addPlanningPass(plan);
  EXPECT_TRUE(s.timings.esdf_updated);
  EXPECT_EQ(s.timings.esdf_ms, 9.0);
  EXPECT_EQ(s.timings.esdf_read_ms, 1.0);
  EXPECT_EQ(s.timings.esdf_propagate_ms, 2.0);
  EXPECT_EQ(s.timings.esdf_transit_ms, 3.0);
  EXPECT_EQ(s.timings.esdf_transit_blocks, 4.0);
  EXPECT_EQ(s.timings.esdf_tsdf_blocks, 5.0);
  EXPECT_EQ(s.timings.esdf_flipped, 6.0);
  EXPECT_EQ(s.timings.esdf_raised, 7.0);
  EXPECT_EQ(s.timings.esdf_lowered, 8.0);
}
