// stats.json: what a run did (FuseReport) and the configuration it ran with.
#include <algorithm>
#include <nlohmann/json.hpp>

#include "fuser/OfflineFuser.h"
#include "stereo_fusion/util/Percentile.h"

namespace stereo_fusion {

namespace {

struct Summary {
  double mean = 0, p50 = 0, p99 = 0;
};

Summary summarize(std::vector<double> v) {
  Summary s;
  if (v.empty()) return s;
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / v.size();
  std::sort(v.begin(), v.end());
  s.p50 = percentileOfSorted(v, 0.50);
  s.p99 = percentileOfSorted(v, 0.99);
  return s;
}

}  // namespace

std::string statsJson(const FuseReport& report, const MapperConfig& config) {
  nlohmann::ordered_json j;
  j["frames"]["total"] = report.frames_total;
  j["frames"]["used"] = report.frames_used;
  j["frames"]["reanchored"] = report.frames_reanchored;
  j["pixels_rejected"]["speckle"] = report.pixels_rejected.speckle_pixels;
  j["pixels_rejected"]["depth_edge"] = report.pixels_rejected.edge_pixels;
  j["pixels_rejected"]["behind_confident_surface"] = report.pixels_contradicting;
  j["disparity_noise_px"] = {{"configured", config.disparity_noise_px},
                             {"measured_p50", summarize(report.disparity_noise_px).p50},
                             {"frames_measured", report.disparity_noise_px.size()}};
  size_t skipped = 0;
  for (const auto& [reason, n] : report.skipped) skipped += n;
  j["frames"]["skipped"] = skipped;
  j["frames"]["skipped_by_reason"] = nlohmann::ordered_json::object();
  for (const auto& [reason, n] : report.skipped) j["frames"]["skipped_by_reason"][reason] = n;
  j["frames"]["skipped_examples"] = report.skipped_examples;
  j["blocks"]["total"] = report.blocks;
  j["blocks"]["meshed_at_8"] = report.blocks_per_level[0];
  j["blocks"]["meshed_at_4"] = report.blocks_per_level[1];
  j["blocks"]["meshed_at_2"] = report.blocks_per_level[2];
  j["blocks"]["seam_filled"] = report.seam_filled_blocks;
  j["blocks"]["evicted"] = report.blocks_evicted;
  j["map"]["loaded_blocks"] = report.blocks_loaded;
  j["memory"]["bytes"] = report.memory_bytes;
  j["memory"]["megabytes"] = report.memory_bytes / 1048576.0;
  j["memory"]["bytes_per_block"] = report.bytes_per_block;
  // Bytes by part, and per level the blocks holding it and its bytes per such block.
  j["memory"]["block_fixed_bytes"] = report.memory.block_bytes;
  j["memory"]["octree_node_bytes"] = report.memory.node_bytes + report.memory.bookkeeping_bytes;
  const char* level_names[kNumLevels] = {"8", "4", "2"};
  for (int level = 0; level < kNumLevels; ++level) {
    auto& l = j["memory"]["levels"][level_names[level]];
    l["blocks"] = report.memory.level_blocks[level];
    l["bytes"] = report.memory.level_bytes[level];
    l["bytes_per_block"] = levelVoxelCount(level) * sizeof(Voxel);
  }
  j["memory"]["peak_rss_megabytes"] = report.peak_rss_bytes / 1048576.0;
  j["memory"]["start_rss_megabytes"] = report.start_rss_bytes / 1048576.0;
  j["memory"]["file_rss_megabytes"] = report.file_rss_bytes / 1048576.0;
  j["memory"]["mesh_store_megabytes"] = report.mesh_store_bytes / 1048576.0;
  j["memory"]["mesh_output_megabytes"] = report.mesh_output_bytes / 1048576.0;
  j["memory"]["dense_grid_megabytes"] = report.dense_grid_bytes / 1048576.0;
  j["memory"]["dense_grid_ratio"] =
      report.memory_bytes > 0 ? report.dense_grid_bytes / report.memory_bytes : 0.0;
  j["mesh"]["vertices"] = report.mesh_vertices;
  j["mesh"]["triangles"] = report.mesh_triangles;
  j["texture"]["textured_blocks"] = report.textured_blocks;
  j["texture"]["bytes"] = report.texture_bytes;
  j["texture"]["megabytes"] = report.texture_bytes / 1048576.0;
  j["texture"]["atlases"] = report.atlas_count;
  // Lookup, fusion and total over every fused frame; meshing and texture over the meshing
  // passes only (one per frame with --mesh-every 1).
  auto stage = [&](double StageTimings::*field, bool mesh_calls_only) {
    std::vector<double> v;
    for (const StageTimings& t : report.timings)
      if (t.meshed || !mesh_calls_only) v.push_back(t.*field);
    const Summary s = summarize(v);
    return nlohmann::ordered_json{{"mean", s.mean},
                                  {"p50", s.p50},
                                  {"p99", s.p99},
                                  {"per", mesh_calls_only ? "mesh call" : "frame"}};
  };
  j["timings_ms"]["lookup"] = stage(&StageTimings::lookup_ms, false);
  j["timings_ms"]["fusion"] = stage(&StageTimings::fusion_ms, false);
  j["timings_ms"]["carve"] = stage(&StageTimings::carve_ms, false);
  j["timings_ms"]["contradiction"] = stage(&StageTimings::contradiction_ms, false);
  j["timings_ms"]["meshing"] = stage(&StageTimings::meshing_ms, true);
  j["timings_ms"]["texture"] = stage(&StageTimings::texture_ms, true);
  j["timings_ms"]["free_space"] = stage(&StageTimings::free_space_ms, false);
  j["timings_ms"]["paging"] = stage(&StageTimings::paging_ms, false);
  {
    std::vector<double> page_ins;  // the frames that brought blocks back
    for (const StageTimings& t : report.timings)
      if (t.page_in_ms > 0.0) page_ins.push_back(t.page_in_ms);
    const Summary s = summarize(page_ins);
    j["timings_ms"]["page_in"] = {
        {"mean", s.mean}, {"p50", s.p50}, {"p99", s.p99}, {"per", "frame that paged in"}};
  }
  const PagingStats& paging = report.paging;
  j["paging"]["max_map_memory_mb"] = config.max_map_memory_mb;
  j["paging"]["map_memory_megabytes"] = report.map_memory_bytes / 1048576.0;
  j["paging"]["map_memory_peak_megabytes"] = paging.map_memory_peak_bytes / 1048576.0;
  j["paging"]["blocks_paged_out_now"] = report.paged_out_blocks;
  j["paging"]["blocks_paged_out"] = paging.blocks_paged_out;
  j["paging"]["blocks_paged_in"] = paging.blocks_paged_in;
  j["paging"]["page_out_passes"] = paging.page_out_passes;
  j["paging"]["writer_waits"] = paging.writer_waits;
  j["paging"]["pages_kept"] = paging.pages_kept;
  j["paging"]["megabytes_written"] = paging.bytes_written / 1048576.0;
  j["paging"]["megabytes_read"] = paging.bytes_read / 1048576.0;
  j["paging"]["page_out_ms"] = paging.page_out_ms;
  j["paging"]["page_in_ms"] = paging.page_in_ms;
  j["paging"]["page_in_max_ms"] = paging.page_in_max_ms;
  j["paging"]["pages_unreadable"] = paging.pages_unreadable;
  j["paging"]["stopped"] = paging.stopped;
  j["paging"]["error"] = paging.error;
  const CheckpointStats& checkpoint = report.checkpoint;
  j["map_store"]["file"] = checkpoint.file;
  j["map_store"]["resumed"] = checkpoint.resumed;
  j["map_store"]["resumed_from_frame"] = report.resumed_from_frame;
  j["map_store"]["checkpoints"] = checkpoint.checkpoints;
  j["map_store"]["last_checkpoint_frames_integrated"] = checkpoint.last_frames_integrated;
  j["map_store"]["blocks_written"] = checkpoint.blocks_written;
  j["map_store"]["blocks_erased"] = checkpoint.blocks_erased;
  j["map_store"]["megabytes_written"] = checkpoint.bytes_written / 1048576.0;
  j["map_store"]["checkpoint_max_ms"] = checkpoint.max_ms;
  j["map_store"]["last_commit_s"] = checkpoint.last_commit_s;
  j["map_store"]["error"] = checkpoint.error;
  {
    // Over the frames after which the planning layer was updated.
    auto overUpdates = [&](double StageTimings::*field) {
      std::vector<double> v;
      for (const StageTimings& t : report.timings)
        if (t.esdf_updated) v.push_back(t.*field);
      return summarize(v);
    };
    const Summary s = overUpdates(&StageTimings::esdf_ms);
    j["timings_ms"]["esdf"] = {
        {"mean", s.mean}, {"p50", s.p50}, {"p99", s.p99}, {"per", "planning update"}};
    j["planning_work_p50"]["read_ms"] = overUpdates(&StageTimings::esdf_read_ms).p50;
    j["planning_work_p50"]["propagate_ms"] = overUpdates(&StageTimings::esdf_propagate_ms).p50;
    j["planning_work_p50"]["transit_ms"] = overUpdates(&StageTimings::esdf_transit_ms).p50;
    j["planning_work_p50"]["transit_blocks"] = overUpdates(&StageTimings::esdf_transit_blocks).p50;
    j["planning_work_p50"]["tsdf_blocks"] = overUpdates(&StageTimings::esdf_tsdf_blocks).p50;
    j["planning_work_p50"]["cells_flipped"] = overUpdates(&StageTimings::esdf_flipped).p50;
    j["planning_work_p50"]["cells_raised"] = overUpdates(&StageTimings::esdf_raised).p50;
    j["planning_work_p50"]["cells_lowered"] = overUpdates(&StageTimings::esdf_lowered).p50;
    j["planning_work_p50"]["free_space_nodes"] =
        stage(&StageTimings::free_space_nodes, false)["p50"];
  }
  j["timings_ms"]["total"] = stage(&StageTimings::total_ms, false);
  size_t mesh_calls = 0;
  for (const StageTimings& t : report.timings) mesh_calls += t.meshed;
  j["timings_ms"]["mesh_calls"] = mesh_calls;
  auto work_column = [&](double StageWork::*field) {
    std::vector<double> v;
    for (const StageWork& w : report.work) v.push_back(w.*field);
    return v;
  };
  auto work = [&](double StageWork::*field) { return summarize(work_column(field)).p50; };
  j["work_per_frame_p50"]["valid_points"] = work(&StageWork::valid_points);
  j["work_per_frame_p50"]["octree_searches"] = work(&StageWork::octree_searches);
  // The lookup's work, which max_lookup_blocks_per_frame bounds.
  j["work_per_frame_p50"]["lookup_box_blocks"] = work(&StageWork::lookup_box_blocks);
  const std::vector<double> box_blocks = work_column(&StageWork::lookup_box_blocks);
  j["work_per_frame_max"]["lookup_box_blocks"] =
      box_blocks.empty() ? 0.0 : *std::max_element(box_blocks.begin(), box_blocks.end());
  j["work_per_frame_p50"]["blocks_queued"] = work(&StageWork::blocks_queued);
  j["work_per_frame_p50"]["blocks_updated"] = work(&StageWork::blocks_updated);
  j["work_per_frame_p50"]["voxels_updated"] = work(&StageWork::voxels_updated);
  j["work_per_frame_p50"]["blocks_carved"] = work(&StageWork::blocks_carved);
  j["work_per_frame_p50"]["voxels_carved"] = work(&StageWork::voxels_carved);
  j["work_per_frame_p50"]["blocks_meshed"] = work(&StageWork::blocks_meshed);
  j["work_per_frame_p50"]["submeshes_changed"] = work(&StageWork::submeshes_changed);
  // Blocks not yet in the map that the frame's bands reached: created (updated) or not allocated.
  j["work_per_frame_p50"]["blocks_created"] = work(&StageWork::blocks_created);
  j["work_per_frame_p50"]["blocks_not_created"] = work(&StageWork::blocks_not_created);
  if (report.correction.applied) {
    const TrajectoryReport& c = report.correction;
    j["trajectory"]["poses"] = c.trajectory_poses;
    j["trajectory"]["matched_poses"] = c.matched_poses;
    j["trajectory"]["frames_refused"] = c.frames_refused;
    j["trajectory"]["frames_rejected"] = c.frames_rejected;
    j["trajectory"]["max_shift_m"] = c.max_shift_m;
    j["trajectory"]["max_rotation_deg"] = c.max_rotation_deg;
    j["trajectory"]["ms"] = c.ms;
  }
  if (report.planning.enabled) {
    const FuseReport::Planning& p = report.planning;
    j["planning"]["cell_m"] = p.cell_m;
    j["planning"]["max_distance_m"] = p.max_distance_m;
    j["planning"]["blocks"] = p.blocks;
    j["planning"]["cells_free"] = p.cells_free;
    j["planning"]["cells_occupied"] = p.cells_occupied;
    if (p.rebuild_ms > 0.0) {  // --time-planning
      j["planning"]["rebuild_ms"] = p.rebuild_ms;
      j["planning"]["query_100k_ms"] = p.query_100k_ms;
    }
    j["planning"]["octomap_cells_skipped"] = p.octomap_cells_skipped;
    j["memory"]["free_space_bytes"] = p.free_space_bytes;
    j["memory"]["free_space_megabytes"] = p.free_space_bytes / 1048576.0;
    j["memory"]["esdf_bytes"] = p.esdf_bytes;
    j["memory"]["esdf_megabytes"] = p.esdf_bytes / 1048576.0;
  }
  j["wall_time_s"] = report.wall_time_s;
  for (const ParameterSpec& p : mapperParameterSpecs())
    j["config"][p.name] = getMapperParameter(config, p.name);
  return j.dump(2);
}

}  // namespace stereo_fusion
