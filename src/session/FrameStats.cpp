#include "stereo_fusion/session/FrameStats.h"

#include "stereo_fusion/Mapper.h"

namespace stereo_fusion {

void StageTimings::addMeshPass(const MeshPass& pass) {
  meshing_ms = pass.mesh.meshing_ms;
  texture_ms = pass.texture.texture_ms;
  meshed = true;
}

void StageTimings::addPlanningPass(const PlanningPass& pass) {
  esdf_ms = pass.esdf_ms;
  esdf_updated = true;
  esdf_read_ms = pass.stats.read_ms;
  esdf_propagate_ms = pass.stats.propagate_ms;
  esdf_transit_ms = pass.stats.transit_ms;
  esdf_transit_blocks = static_cast<double>(pass.stats.transit_allocated);
  esdf_tsdf_blocks = static_cast<double>(pass.stats.tsdf_blocks);
  esdf_flipped = static_cast<double>(pass.stats.esdf.cells_flipped);
  esdf_raised = static_cast<double>(pass.stats.esdf.cells_raised);
  esdf_lowered = static_cast<double>(pass.stats.esdf.cells_lowered);
}

FrameStats frameStats(const IntegrationResult& r, bool meshed) {
  FrameStats s;
  StageTimings& t = s.timings;
  t.lookup_ms = r.lookup_ms;
  t.fusion_ms = r.fusion_ms;
  t.carve_ms = r.carve_ms;
  t.meshing_ms = r.mesh.meshing_ms;
  t.texture_ms = r.texture.texture_ms;
  t.meshed = meshed;
  t.free_space_ms = r.free_space_ms;
  t.contradiction_ms = r.contradiction_ms;
  t.free_space_nodes = static_cast<double>(r.free_space.nodes_visited);
  t.paging_ms = r.paging_ms;
  t.page_in_ms = r.page_in_ms;
  s.work = {static_cast<double>(r.lookup.valid_points),
            static_cast<double>(r.lookup.octree_searches),
            static_cast<double>(r.lookup.blocks_queued),
            static_cast<double>(r.fusion.blocks_updated),
            static_cast<double>(r.fusion.voxels_updated),
            static_cast<double>(r.mesh.blocks_meshed),
            static_cast<double>(r.mesh.changed.size()),
            static_cast<double>(r.fusion.blocks_created),
            static_cast<double>(r.fusion.blocks_not_created),
            static_cast<double>(r.carve.blocks_carved),
            static_cast<double>(r.carve.voxels_carved),
            static_cast<double>(r.lookup.box_blocks)};
  s.mesh_pass_ran = !r.mesh.changed.empty() || !r.mesh.removed.empty() || r.mesh.blocks_meshed > 0;
  return s;
}

void FusedFrameTotals::add(const IntegrationResult& r) {
  speckle_pixels += r.rejected.speckle_pixels;
  edge_pixels += r.rejected.edge_pixels;
  contradicting_pixels += r.contradiction.pixels_rejected;
  if (r.reanchored) ++reanchored;
}

}  // namespace stereo_fusion
