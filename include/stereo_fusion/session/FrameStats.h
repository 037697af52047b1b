#pragma once
// What a fused frame's IntegrationResult (and the passes after it) says for the statistics: the
// one place that turns it into numbers, for the node's /diagnostics and the offline fuser's
// stats.json alike.
#include <atomic>
#include <cstdint>

namespace stereo_fusion {

struct IntegrationResult;
struct MeshPass;
struct PlanningPass;

/// Per-frame stage timings in milliseconds: lookup and fusion of the frame, and the meshing
/// pass (with its texture pass) that followed it, if one did (`meshed`); total is all of it.
struct StageTimings {
  double lookup_ms = 0, fusion_ms = 0, carve_ms = 0, meshing_ms = 0, texture_ms = 0, total_ms = 0;
  bool meshed = false;
  double free_space_ms = 0;     ///< recording the space the frame saw empty (planning layer)
  double contradiction_ms = 0;  ///< dropping isolated contradictions (ContradictionFilter)
  double esdf_ms = 0;           ///< the planning update after this frame (with `esdf_updated`)
  bool esdf_updated = false;
  /// That update's work: TSDF blocks re-read, cells flipped (occupied ↔ not), raised, lowered.
  double esdf_read_ms = 0, esdf_propagate_ms = 0, esdf_transit_ms = 0, esdf_tsdf_blocks = 0,
         esdf_flipped = 0, esdf_raised = 0, esdf_lowered = 0, esdf_transit_blocks = 0;
  double free_space_nodes = 0;  ///< octree nodes the free-space recording tested
  /// Paging (max_map_memory_mb): before the frame (page-in) and after it (page-out), and the
  /// page-in alone.
  double paging_ms = 0, page_in_ms = 0;

  /// Lookup, fusion and carving (fusion with carving: the frame's update of the map).
  double mapUpdateMs() const { return lookup_ms + fusion_ms + carve_ms; }
  /// The frame's stages and its meshing pass, summed (the node's "total").
  double stagesMs() const { return mapUpdateMs() + meshing_ms + texture_ms; }
  /// The meshing pass `pass` ran after the frame (a deferred one).
  void addMeshPass(const MeshPass& pass);
  /// The planning update `pass` ran after the frame.
  void addPlanningPass(const PlanningPass& pass);
};

/// How much work one frame made each stage do (what the timings above are spent on).
struct StageWork {
  double valid_points = 0, octree_searches = 0, blocks_queued = 0, blocks_updated = 0,
         voxels_updated = 0, blocks_meshed = 0, submeshes_changed = 0, blocks_created = 0,
         blocks_not_created = 0, blocks_carved = 0, voxels_carved = 0, lookup_box_blocks = 0;
};

/// One fused frame as the statistics read it.
struct FrameStats {
  StageTimings timings;  ///< total_ms left 0: the caller times what it counts as the frame
  StageWork work;
  /// True if the frame ran a meshing pass that changed or visited something.
  bool mesh_pass_ran = false;
};
/// `result` of a fused frame; `meshed`: it was integrated with MeshTiming::kNow.
FrameStats frameStats(const IntegrationResult& result, bool meshed);

/// Sums over the fused frames (the session counts them in fuse(); readable from any thread).
struct FusedFrameTotals {
  std::atomic<uint64_t> speckle_pixels{0};        ///< OutlierRejection
  std::atomic<uint64_t> edge_pixels{0};           ///< OutlierRejection
  std::atomic<uint64_t> contradicting_pixels{0};  ///< ContradictionFilter
  std::atomic<uint64_t> reanchored{0};  ///< accepted as a relocalisation / clock reset (FrameGate)
  void add(const IntegrationResult& result);
};

}  // namespace stereo_fusion
