#include "stereo_fusion/MapperConfig.h"

#include <cmath>

#include "stereo_fusion/integration/FrameGate.h"

namespace stereo_fusion {

namespace {

using Table = ParameterTable<MapperConfig>;

template <typename T>
Table::Field<T> member(T MapperConfig::*m) {
  return Table::member(m);
}

const Table& table() {
  static const Table parameters = [] {
    Table t;
    t.addDouble("voxel_size_m", "m", 0.002, true, 1.0,
                "Edge of a finest-level (8³) voxel; a block is 8 voxels wide.",
                member(&MapperConfig::voxel_size_m));
    t.addDouble("truncation_vox", "vox", 1.0, true, 8.0,
                "Truncation distance Φ in voxels of the measurement's level: "
                "Φ = truncation_vox · s · voxel_size_m (s = 1, 2, 4), at least 2 voxels "
                "of the level being updated. At most 8: beyond, a far point's band "
                "spans dozens of blocks.",
                member(&MapperConfig::truncation_vox));
    t.addDouble("min_depth_m", "m", 0.0, true, 1000.0, "Measurements nearer than this are ignored.",
                member(&MapperConfig::min_depth_m));
    t.addDouble("max_depth_m", "m", 0.0, false, 1000.0,
                "Measurements farther than this are ignored (stereo error grows as z²).",
                member(&MapperConfig::max_depth_m));
    t.addEnum<LevelMode>(
        "level_mode", {{"noise", LevelMode::kNoise}, {"depth", LevelMode::kDepth}},
        "Where measurements switch to the coarser levels (eq. 3.2). noise: from the camera, at the "
        "depth where the stereo depth error z²·σ_d/(f·b) exceeds a level's voxel edge: the 4³ "
        "level "
        "from √(voxel_size_m·f·b/σ_d), 2³ from √2 times that (σ_d = disparity_noise_px), so a "
        "precise or long-baseline camera stays fine farther. depth: at scale2_min_depth_m and "
        "scale4_min_depth_m whatever the camera (the thesis).",
        member(&MapperConfig::level_mode));
    t.addDouble("disparity_noise_px", "px", 0.0, false, 100.0,
                "Expected disparity error (1σ) of the disparity source, for "
                "level_mode noise. 0.15 suits OpenCV SGBM on well-textured images and "
                "depth cameras converted to disparity; raise it for noisier matching "
                "(coarser levels sooner). A source whose disparities come in coarse "
                "steps (DisparityImage.delta_d) uses at least their rounding error "
                "delta_d/√12 (0.29 px for whole pixels).",
                member(&MapperConfig::disparity_noise_px));
    t.addInt("speckle_max_area_px", "px", 0, 1 << 20,
             "Outlier rejection: a blob of at most this many pixels whose 4-neighbours' "
             "disparities differ by at most speckle_max_diff_px is rejected as an isolated "
             "mismatch (OpenCV filterSpeckles). 0 (default) = off: OpenCV SGBM and "
             "stereo_image_proc filter speckles themselves (on their frames the pass found "
             "~10 more pixels per 640×480 frame, for 1.5 ms); ~100 suits a matcher that "
             "does not.",
             member(&MapperConfig::speckle_max_area_px));
    t.addDouble("speckle_max_diff_px", "px", 0.0, false, 100.0,
                "Outlier rejection: neighbouring disparities within this of each other "
                "belong to one blob (speckle_max_area_px).",
                member(&MapperConfig::speckle_max_diff_px));
    t.addInt("edge_reject_radius_px", "px", 0, 16,
             "Outlier rejection at depth edges: a pixel with a usable neighbour within this "
             "radius (square window) whose disparity is smaller by more than "
             "edge_reject_jump_px is rejected: the near side of an edge, where block "
             "matching lends the foreground's disparity to the background (fattening) and "
             "leaves surface floating in front of it. 0 = off.",
             member(&MapperConfig::edge_reject_radius_px));
    t.addDouble("edge_reject_jump_px", "px", 0.0, false, 1000.0,
                "Disparity step that counts as a depth edge for edge_reject_radius_px. A "
                "plane's disparity changes by at most b/D px per pixel (D: its distance from "
                "the camera centre), so planes farther than radius·b/jump are never cut.",
                member(&MapperConfig::edge_reject_jump_px));
    t.addBool("contradiction_filter",
              "Robust fusion against mismatches that repeat across neighbouring views: a "
              "measurement beyond every confident surface of its 8×8-px tile by more than "
              "contradiction_sigmas σ_z is dropped before fusion when it is isolated "
              "(ContradictionFilter), so a matcher's errors do not grow a second skin behind "
              "well-observed walls; where many measurements around it do the same (an object "
              "left) it is kept and carving clears the map. Counted as 'pixels rejected: behind "
              "a confident surface'. false: every measurement is fused.",
              member(&MapperConfig::contradiction_filter));
    t.addDouble("contradiction_min_weight", "", 0.0, false, 1e6,
                "contradiction_filter: voxel weight from which a surface counts as confident "
                "(about the number of frames that agree on it, less what the free-space decay "
                "took).",
                member(&MapperConfig::contradiction_min_weight));
    t.addDouble("contradiction_sigmas", "", 0.0, false, 100.0,
                "contradiction_filter: how far behind a confident surface a measurement must "
                "lie to contradict it, in depth errors σ_z = z²·disparity_noise_px/(f·b) at its "
                "depth (plus a voxel of the surface's level).",
                member(&MapperConfig::contradiction_sigmas));
    t.addDouble("contradiction_max_share", "", 0.0, true, 1.0,
                "contradiction_filter: a contradicting measurement is dropped only while at most "
                "this share of the usable measurements of the 5×5 tiles (40×40 px) around it "
                "contradict too; more means the world changed there.",
                member(&MapperConfig::contradiction_max_share));
    t.addDouble("scale2_min_depth_m", "m", 0.0, false, 1000.0,
                "level_mode depth: depth from which a measurement is fused at the 4³ "
                "level and coarser (eq. 3.2; thesis: 2 m).",
                [](MapperConfig& c) -> double& { return c.levels.scale2_min_depth_m; });
    t.addDouble("scale4_min_depth_m", "m", 0.0, false, 1000.0,
                "level_mode depth: depth from which a measurement is fused at the 2³ "
                "level only (eq. 3.2; thesis: 4 m).",
                [](MapperConfig& c) -> double& { return c.levels.scale4_min_depth_m; });
    t.addBool("update_allocated_finer_level",
              "A measurement also updates the next finer level of a block where that level "
              "is already allocated (by nearer views), with its own band and a quarter of its "
              "weight (its depth error is up to twice the level's own); it never allocates a "
              "level. Surfaces seen near and then from farther, at grazing angles or past a "
              "level switch, stay complete at the fine level; memory is unchanged. false: a "
              "measurement updates its own level and the coarser ones only (the thesis).",
              member(&MapperConfig::update_allocated_finer_level));
    t.addEnum<WeightMode>(
        "weight_mode",
        {{"constant", WeightMode::kConstant},
         {"steinbruecker", WeightMode::kSteinbruecker},
         {"depth_aware", WeightMode::kDepthAware}},
        "Measurement weight: constant 1; Steinbrücker fall-off behind the surface (eq. 3.10); "
        "or that fall-off × (depth_weight_reference_m / z)².",
        member(&MapperConfig::weight_mode));
    t.addDouble("weight_falloff_start_vox", "vox", 0.0, true, 8.0,
                "δ of eq. 3.10: behind the surface the weight falls linearly from 1 at δ "
                "to 0 at Φ (voxels of the measurement's level; must be < truncation_vox).",
                member(&MapperConfig::weight_falloff_start_vox));
    t.addDouble("depth_weight_reference_m", "m", 0.0, false, 100.0,
                "Depth at which the depth-aware weight equals 1.",
                member(&MapperConfig::depth_weight_reference_m));
    t.addDouble("max_weight", "", 0.0, false, 1e6,
                "Cap on a voxel's cumulative weight, so the map keeps adapting.",
                member(&MapperConfig::max_weight));
    t.addBool("free_space_carving",
              "Free-space evidence: the observed voxels of blocks in view that lie in front of "
              "the measured surface by more than fusion's band are updated towards free space, "
              "at every level, so people who walked on and stereo floaters fade (FreeSpaceCarver); "
              "fusion lets contradicted voxels decay (free_space_decay). false: the thesis' plain "
              "running average.",
              member(&MapperConfig::free_space_carving));
    t.addDouble("free_space_decay", "", 0.0, true, 0.99,
                "Share of a voxel's weight that one frame seeing through it removes before "
                "fusing -Φ, and that fusion removes where a measurement contradicts the stored "
                "value by more than the band (|D - d| > Φ): recent evidence wins, a surface seen "
                "through ~10-15 times is gone whatever its history. 0: plain averaging.",
                member(&MapperConfig::free_space_decay));
    t.addInt("free_space_window_px", "px", 0, 16,
             "A voxel counts as seen through only if every pixel within this radius of its "
             "projection has a measurement beyond it: depth edges, thin structures and the "
             "matcher's gaps are not carved.",
             member(&MapperConfig::free_space_window_px));
    t.addEnum<LookupMode>(
        "lookup_mode", {{"naive", LookupMode::kNaive}, {"accelerated", LookupMode::kAccelerated}},
        "Octree lookup: Algorithm 1 (search per pixel) or Algorithm 2 (search per distinct block "
        "per image region).",
        member(&MapperConfig::lookup_mode));
    t.addInt("lookup_region_px", "px", 1, 512,
             "Edge of the square image regions of Algorithm 2 and the histogram filter.",
             member(&MapperConfig::lookup_region_px));
    t.addInt("histogram_min_points", "points", 0, 1 << 20,
             "Histogram filter (Alg. 2): a block reached by fewer points of one image "
             "region is not queued from that region. The threshold is scaled by the share "
             "of the region's pixels that hold a measurement (at least 1), so a sparsely "
             "matched region (weak texture, far surfaces) keeps its blocks while a dense "
             "one drops its isolated outliers; 0 disables the filter.",
             member(&MapperConfig::histogram_min_points));
    t.addInt("num_threads", "", 0, 256,
             "Threads for lookup and fusion, the caller included; 0 = all cores.",
             member(&MapperConfig::num_threads));
    t.addBool("use_color", "Fuse the colour image into per-voxel colour.",
              member(&MapperConfig::use_color));
    t.addBool("mesh_enabled",
              "Re-mesh the changed blocks after every frame (incremental marching cubes).",
              member(&MapperConfig::mesh_enabled));
    t.addDouble("mesh_level_min_coverage", "", 0.0, false, 1.0,
                "A block is meshed at the finest level whose observed surface area is at "
                "least this share of the largest among its three levels.",
                member(&MapperConfig::mesh_level_min_coverage));
    t.addBool("mesh_fill_seams",
              "Where a block is meshed at a finer level than it holds, its unobserved face "
              "voxels take the value of its own coarser levels, so a fine block meets a "
              "coarser neighbour without a hole. false: those cells are skipped (the "
              "thesis).",
              member(&MapperConfig::mesh_fill_seams));
    t.addEnum<TextureMode>(
        "texture", {{"off", TextureMode::kOff}, {"patches", TextureMode::kPatches}},
        "Colour of the exported / published mesh: vertex colours only, or also one image patch "
        "per submesh cut from the best view (thesis §3.6 method B); patches add mesh.obj + .mtl + "
        "atlas PNGs to scripts/fuse.sh and textures to ~mesh_update. Needs mesh_enabled.",
        member(&MapperConfig::texture));
    t.addInt("texture_border_px", "px", 0, 1000,
             "A frame textures a block only if every vertex of its submesh projects at "
             "least this far inside the image (thesis: 24 px), so border submeshes are "
             "fully covered.",
             member(&MapperConfig::texture_border_px));
    t.addInt("texture_max_patch_px", "px", 4, 1024,
             "Cap on a texture patch's width and height; larger crops are downscaled. "
             "Bounds texture memory to 3 · cap² bytes per block.",
             member(&MapperConfig::texture_max_patch_px));
    t.addInt("max_blocks", "blocks", 0, 100000000,
             "Memory budget: after each frame, while the map holds more blocks (0.3–7 KB "
             "each by the levels they hold), the least recently updated ones (farthest "
             "first among equals) are evicted and their submeshes removed. 0 = unlimited.",
             member(&MapperConfig::max_blocks));
    t.addDouble("min_coherent_pixel_share", "", 0.0, true, 1.0,
                "A frame is rejected before the lookup, the map unchanged, when fewer of "
                "its usable disparities than this share agree within 0.5 px with one of "
                "their 8 neighbours: random values from a broken matcher or a wrong topic "
                "(about 12 % agree over 0–64 px) would put a point anywhere along every "
                "ray. Real stereo and depth cameras measure 99.8–100 %. Frames with fewer "
                "than 64 usable pixels are not judged. 0 = no check.",
                member(&MapperConfig::min_coherent_pixel_share));
    t.addInt("max_lookup_blocks_per_frame", "blocks", 0, 2000000000,
             "Work bound of one frame's lookup: the blocks its truncation bands' boxes span "
             "(summed over the distinct boxes of each image region; with lookup_mode naive, "
             "over every pixel's box). A frame over it is dropped before any block is visited "
             "('dropped: lookup work bound'), the map unchanged: an absurd calibration or "
             "depth range cannot stall the node. Measured maxima: a 640×480 frame at 1 cm "
             "0.56 M (naive 6.1 M), KITTI's 1241×376 at 1 cm to 40 m 6.4 M; at ~8 ns a "
             "block (accelerated) the default bounds the lookup to ~0.2 s. 0 = no limit.",
             member(&MapperConfig::max_lookup_blocks_per_frame));
    t.addInt("max_new_blocks_per_frame", "blocks", 0, 100000000,
             "Allocation budget of one frame: a frame whose truncation bands reach more "
             "blocks that are not yet in the map is rejected before fusion, the map "
             "unchanged (so a frame allocates at most this many blocks, 0.3–7 KB each). "
             "A real 640×480 frame at 1 cm adds up to ~10 000 (first frame); raise it for "
             "larger images or finer voxels (it grows with pixels / voxel²). 0 = no limit.",
             member(&MapperConfig::max_new_blocks_per_frame));
    t.addDouble("max_distance_from_camera_m", "m", 0.0, true, 1e6,
                "After each frame, blocks whose centre is farther than this from the "
                "camera are evicted and their submeshes removed. 0 = unlimited; "
                "otherwise at least max_depth_m.",
                member(&MapperConfig::max_distance_from_camera_m));
    t.addDouble("max_map_memory_mb", "MB", 0.0, true, 1e9,
                "Memory cap of the map (all layers: TSDF, mesh, textures, planning). Beyond it "
                "the blocks least likely to be needed (not updated for longest, then farthest "
                "from the camera) are paged out to the block store with their submeshes and "
                "texture patches, and paged back in before a frame, a mesh pass or a clear "
                "reaches them: every output is byte-identical to an uncapped run. The planning "
                "layer stays in memory (it counts towards the cap). Keep it above a frame's "
                "working set (the blocks within max_depth_m in view). 0 = unlimited, no store.",
                member(&MapperConfig::max_map_memory_mb));
    t.addString("map_store_path", true, "a folder; empty: the temporary folder",
                "Where max_map_memory_mb pages blocks to: a folder that gets one SQLite file per "
                "map (pages-<pid>-<n>.sqlite, removed when the map is); with checkpoint_period_s "
                "or resume also the map store map.sqlite, the map kept across runs. Put it on a "
                "disk with room for the whole map (~2-7 KB a block, twice with both).",
                member(&MapperConfig::map_store_path));
    t.addDouble("checkpoint_period_s", "s", 0.0, true, 1e6,
                "> 0: the map store map_store_path/map.sqlite keeps the map: every this many "
                "seconds (and at ~save_map with an empty path, and when the offline fuser ends) "
                "the blocks changed since the last checkpoint are written to it in one "
                "transaction, on a thread of their own. A kill (SIGKILL, power cut) loses at most "
                "the frames since the last checkpoint; resume continues from it. 0 = no "
                "checkpoints (without resume, the store is not kept).",
                member(&MapperConfig::checkpoint_period_s));
    t.addBool("resume",
              "Continue the map kept in map_store_path/map.sqlite, as it was at its last "
              "checkpoint, mesh and texture patches included (the planning layer is derived "
              "again). No store there: a new map. A store that cannot be read, or was made for "
              "another voxel grid, is left untouched: the error is reported and the node maps "
              "without it.",
              member(&MapperConfig::resume));
    // The frame gate's rule, stated where it is documented (FrameGate::kFramesToReanchor).
    const std::string reanchor_frames = std::to_string(FrameGate::kFramesToReanchor);
    t.addDouble("max_pose_jump_m", "m", 0.0, true, 1e6,
                "A frame whose camera is farther than this from the last fused frame's "
                "camera is rejected (a SLAM glitch); a rejected frame never becomes the "
                "reference, and after " +
                    reanchor_frames +
                    " rejected frames that agree with "
                    "each other (a relocalisation) the last is fused and becomes it. 0 = no check.",
                member(&MapperConfig::max_pose_jump_m));
    t.addDouble("max_timestamp_gap_s", "s", 0.0, true, 1e9,
                "A frame stamped more than this after the last fused frame is rejected "
                "(a stamp far in the future would otherwise make every later frame go "
                "\"backwards\"); " +
                    reanchor_frames +
                    " consecutive frames that agree with "
                    "each other are accepted as a clock jump. 0 = no check.",
                member(&MapperConfig::max_timestamp_gap_s));
    t.addBool("require_increasing_timestamps",
              "Reject a frame whose timestamp is before (backwards) or equal to "
              "(duplicate) the last fused frame's; " +
                  reanchor_frames +
                  " consecutive later "
                  "frames that agree with each other are accepted as a clock reset. Timestamp 0 "
                  "means unknown "
                  "and is not checked (the nodelet drops ROS messages stamped 0).",
              member(&MapperConfig::require_increasing_timestamps));
    t.addBool("planning_enabled",
              "Keep the planning layer (planning/): the space each frame saw empty, an "
              "occupied / free / unknown state per cell, and a Euclidean signed distance "
              "field (ESDF) over it, for distance queries, the occupancy grid and esdf.ply. "
              "false: the map holds surfaces only.",
              member(&MapperConfig::planning_enabled));
    t.addDouble("esdf_voxel_size_m", "m", 0.0, true, 1.0,
                "Cell edge of the planning layer (free space, occupancy, ESDF): "
                "voxel_size_m times 1, 2, 4 or 8. 0 = auto: the one of those nearest in ratio "
                "to max(8 cm, range / 128), the range being max(max_depth_m, "
                "free_space_unmeasured_range_m): indoors (8 m) 4 voxels at 2 cm, 8 at 1 cm, 1 at "
                "10 cm; a 10 cm map out to 25 m gets 20 cm cells (a ray crosses at most ~128 "
                "cells: past ~10 m stereo cannot resolve 8 cm, and each cell costs the frame).",
                member(&MapperConfig::esdf_voxel_size_m));
    t.addDouble("esdf_max_distance_m", "m", 0.0, false, 100.0,
                "The ESDF is exact up to this distance from the nearest obstacle; "
                "farther cells read this value (\"at least\"). At most 100 cells.",
                member(&MapperConfig::esdf_max_distance_m));
    t.addDouble("free_space_unmeasured_range_m", "m", 0.0, true, 1000.0,
                "Pixels without a measurement count as seeing free space up to this "
                "depth (a sky, a far open field the matcher cannot reach). 0 = off: only "
                "rays with a measurement mark space free, up to their depth minus the band.",
                member(&MapperConfig::free_space_unmeasured_range_m));
    t.addDouble("occupancy_min_weight", "", 0.0, false, 1e6,
                "Evidence for the planning layer: a TSDF voxel counts towards a cell's "
                "occupied / free state only once its weight reaches this (about the number of "
                "views that agree on it, less what carving's decay took). A cell is occupied "
                "when the finest level with evidence over it has an evidence voxel on or behind "
                "the surface, so one view of a mismatch is no obstacle, and one that later "
                "views see through decays until it is free. At most max_weight. Sparse "
                "outdoor views (a car's stereo at 10 cm voxels) rarely reach 2: use 1 there "
                "(doc/performance.md).",
                member(&MapperConfig::occupancy_min_weight));
    t.addDouble("grid_min_z_m", "m", -1e4, true, 1e4,
                "Lower bound of the height band (world z) that the 2D occupancy grid "
                "(occupancy.pgm, ~occupancy_grid) projects.",
                member(&MapperConfig::grid_min_z_m));
    t.addDouble("grid_max_z_m", "m", -1e4, true, 1e4,
                "Upper bound of the occupancy grid's height band (world z).",
                member(&MapperConfig::grid_max_z_m));
    t.addInt("grid_max_cells", "cells", 10000, 1000000000,
             "Largest 2D occupancy grid (~occupancy_grid, occupancy.pgm): a map whose known "
             "columns span more is given as a square window of at most sqrt(grid_max_cells) "
             "cells a side around the camera, kept inside the known extent (a WARN on "
             "/diagnostics; 'occupancy grid windowed' in the offline log). 4194304 = 2048 x "
             "2048: 164 m at 8 cm cells, 4 MB a message.",
             member(&MapperConfig::grid_max_cells));
    return t;
  }();
  return parameters;
}

}  // namespace

double MapperConfig::planningCellSizeM() const {
  if (esdf_voxel_size_m > 0.0) return esdf_voxel_size_m;
  // Free space is carved along every ray out to the range: past ~10 m, cells that keep a ray
  // to kAutoPlanningCellRays cells follow stereo's depth error (it grows as z²) instead of
  // costing the frame ever more cells of an 8 cm grid it cannot resolve there.
  constexpr double kAutoPlanningCellM = 0.08;
  constexpr double kAutoPlanningCellRays = 128.0;
  const double range_m = std::max(max_depth_m, free_space_unmeasured_range_m);
  const double target_m = std::max(kAutoPlanningCellM, range_m / kAutoPlanningCellRays);
  double best = voxel_size_m;
  for (int n : {2, 4, 8})
    if (std::abs(std::log(n * voxel_size_m / target_m)) < std::abs(std::log(best / target_m)))
      best = n * voxel_size_m;
  return best;
}

const std::vector<ParameterSpec>& mapperParameterSpecs() { return table().specs(); }

bool setMapperParameter(MapperConfig* config, const std::string& name, const std::string& value,
                        std::string* error) {
  return table().set(config, name, value, error);
}

std::string getMapperParameter(const MapperConfig& config, const std::string& name) {
  return table().get(config, name);
}

std::vector<std::string> validateMapperConfig(const MapperConfig& config) {
  // Range checks: re-apply every value through its setter, which owns the range.
  std::vector<std::string> errors = table().rangeErrors(config);
  if (config.min_depth_m >= config.max_depth_m)
    errors.push_back("min_depth_m must be < max_depth_m");
  if (config.levels.scale2_min_depth_m > config.levels.scale4_min_depth_m)
    errors.push_back("scale2_min_depth_m must be <= scale4_min_depth_m");
  if (config.weight_falloff_start_vox >= config.truncation_vox)
    errors.push_back("weight_falloff_start_vox must be < truncation_vox");
  // Patches are cut from the frame being fused, right after its meshing pass.
  if (config.texture == TextureMode::kPatches && !config.mesh_enabled)
    errors.push_back("texture = patches needs mesh_enabled = true");
  // A distance bound below the fusion range would evict surfaces in the frame that fused them.
  if (config.max_distance_from_camera_m > 0.0 &&
      config.max_distance_from_camera_m < config.max_depth_m)
    errors.push_back(
        "max_distance_from_camera_m must be 0 (off) or >= max_depth_m, else blocks fused "
        "from a frame are evicted by the same frame");
  if (config.esdf_voxel_size_m > 0.0) {
    const double n = config.esdf_voxel_size_m / config.voxel_size_m;
    const double nearest = std::round(n);
    if (std::abs(n - nearest) > 1e-6 * n ||
        (nearest != 1 && nearest != 2 && nearest != 4 && nearest != 8))
      errors.push_back("esdf_voxel_size_m must be 0 (auto) or voxel_size_m times 1, 2, 4 or 8");
  }
  // A voxel's weight never exceeds max_weight: a larger minimum would leave no cell occupied.
  if (config.planning_enabled && config.occupancy_min_weight > config.max_weight)
    errors.push_back("occupancy_min_weight must be at most max_weight (a voxel never weighs more)");
  if (config.planning_enabled && config.esdf_max_distance_m > 100.0 * config.planningCellSizeM())
    errors.push_back("esdf_max_distance_m must be at most 100 planning cells (esdf_voxel_size_m)");
  if (config.grid_min_z_m >= config.grid_max_z_m)
    errors.push_back("grid_min_z_m must be < grid_max_z_m");
  if (config.keepsMapStore() && config.map_store_path.empty())
    errors.push_back(
        "checkpoint_period_s and resume need map_store_path: the folder of the map store");
  return errors;
}

}  // namespace stereo_fusion
