#pragma once
// The offline reconstruction of scripts/fuse.sh: a dataset folder in, mesh.ply and
// stats.json out, with the same pipeline (lookup → fusion → incremental meshing) as the node.

#include <map>
#include <string>
#include <vector>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/integration/OutlierRejection.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/ros/BagSequence.h"
#include "stereo_fusion/paging/CheckpointState.h"
#include "stereo_fusion/paging/PagingConfig.h"
#include "stereo_fusion/session/FrameStats.h"

namespace stereo_fusion {

/// What to fuse and where to write it.
struct FuseOptions {
  std::string input;     ///< dataset folder, or a rosbag (*.bag)
  BagTopics bag_topics;  ///< topics and world frame read from a bag (the nodelet's defaults)
  std::string out_dir;  ///< receives mesh.ply and stats.json (and mesh.obj + .mtl + atlas PNGs with
                        ///< texture = patches)
  MapperConfig config;
  size_t max_frames = 0;  ///< 0 = all
  /// Bring the mesh up to date after every N-th fused frame (and after the last): 1 = every
  /// frame, as the nodelet with mesh_publish_rate_hz 0.
  size_t mesh_every = 1;
  /// The planning layer's occupancy and ESDF are brought up to date after every N-th fused
  /// frame and after the last (--esdf-every). 10: the distance field's wavefronts from ten
  /// frames overlap, so an update every tenth frame costs ~4× one update, not 10× (hall, 2 cm).
  size_t esdf_every = 10;
  std::string
      load_map;  ///< map file to start from (empty = an empty map); `input` may then be empty
  std::string save_map;  ///< where to save the map after the last frame (empty = not saved)
  bool progress = true;  ///< progress bar on stderr (a line per 10 % when not a terminal)
  /// --frame-log: a line "<input frame> <unix time s>" appended (and flushed) after every fused
  /// frame, for a harness that kills the fuser and asks what it had fused (the kill loop).
  std::string frame_log;
  /// --time-planning: after the outputs, time a 100 000-point batch query and a batch rebuild of
  /// the planning layer (stats.json planning.query_100k_ms, rebuild_ms; scripts/bench_planning.sh).
  bool time_planning = false;
  /// A SLAM's corrected camera poses (TUM lines, stamps matching the frames'), applied after the
  /// last frame: the frames are fused again at their corrected poses (empty = none).
  std::string trajectory;
  /// What parseFuseArguments() tells the user without failing (node parameters of --config or
  /// --set that the fuser ignores); fuse_main prints them unless --quiet.
  std::vector<std::string> notes;
};

/// What --trajectory did.
struct TrajectoryReport {
  bool applied = false;
  size_t trajectory_poses = 0;  ///< usable lines of the file
  size_t matched_poses =
      0;  ///< of those, within 0.5 s of a fused frame (they define the correction)
  size_t frames_refused = 0;   ///< frames fused again at their corrected poses
  size_t frames_rejected = 0;  ///< of those, rejected at the corrected pose (by the FrameGate)
  double max_shift_m = 0.0;    ///< the largest move of a camera centre
  double max_rotation_deg = 0.0;
  double ms = 0.0;  ///< re-fusing and re-meshing
};

/// What a run did; stats.json is this, plus the configuration.
struct FuseReport {
  size_t frames_total = 0;
  size_t frames_used = 0;
  size_t frames_reanchored =
      0;  ///< of those, accepted as a relocalisation / clock reset (FrameGate)
  OutlierRejectionStats pixels_rejected;      ///< summed over the used frames (OutlierRejection)
  uint64_t pixels_contradicting = 0;          ///< summed over the used frames (ContradictionFilter)
  std::vector<double> disparity_noise_px;     ///< per used frame, where measured (DisparityNoise)
  std::map<std::string, size_t> skipped;      ///< reason → count (the session's RejectCounters)
  std::vector<std::string> skipped_examples;  ///< the first few messages, verbatim
  std::vector<StageTimings> timings;          ///< one per used frame
  std::vector<StageWork> work;                ///< one per used frame
  size_t blocks = 0;            ///< in memory at the end (paged-out ones in `paged_out_blocks`)
  size_t paged_out_blocks = 0;  ///< in the block store at the end (max_map_memory_mb)
  size_t map_memory_bytes = 0;  ///< every layer in memory at the end (Mapper::mapMemoryBytes())
  PagingStats paging;
  CheckpointStats checkpoint;     ///< the map store's (file empty: none)
  size_t blocks_loaded = 0;       ///< blocks of the --load-map file
  size_t resumed_from_frame = 0;  ///< resume: the input frame the stored map continued at
  uint64_t blocks_evicted = 0;    ///< by the memory bound (max_blocks, max_distance_from_camera_m)
  size_t blocks_per_level[3] = {0, 0, 0};  ///< by the level each block is meshed at
  size_t seam_filled_blocks =
      0;  ///< blocks meshed with faces filled from coarser levels (mesh_fill_seams)
  size_t memory_bytes = 0;
  double bytes_per_block = 0;
  BlockOctree::MemoryUse memory;  ///< memory_bytes by part: blocks, voxel levels, nodes
  double peak_rss_bytes = 0;      ///< the whole process's peak resident set (getrusage)
  /// Where the peak goes besides the map: the process before the first frame (program,
  /// libraries, session), the pages of the program's and libraries' files at the end, the
  /// submeshes kept for incremental meshing and the welded mesh written to mesh.ply.
  double start_rss_bytes = 0, file_rss_bytes = 0;
  size_t mesh_store_bytes = 0, mesh_output_bytes = 0;
  /// A dense grid of finest-level voxels (same 12-byte voxel) over the blocks' bounding box:
  /// what the sparse block octree saves.
  double dense_grid_bytes = 0;
  size_t mesh_vertices = 0, mesh_triangles = 0;
  size_t textured_blocks = 0;  ///< blocks with a texture patch (texture = patches)
  size_t texture_bytes = 0;    ///< memory held by the texture patches
  size_t atlas_count = 0;      ///< atlas PNGs written with mesh.obj
  double wall_time_s = 0;
  TrajectoryReport correction;
  /// The planning layer at the end (planning_enabled).
  struct Planning {
    bool enabled = false;
    double cell_m = 0, max_distance_m = 0;
    size_t blocks = 0, cells_free = 0, cells_occupied = 0;
    size_t free_space_bytes = 0, esdf_bytes = 0;
    double rebuild_ms = 0;  ///< with --time-planning: a batch rebuild of the whole layer
    double query_100k_ms =
        0;  ///< with --time-planning: sampleBatch() of 100 000 points in the known cells' box
    size_t octomap_cells_skipped = 0;
  } planning;
};

/// Runs the reconstruction. Frames that cannot be read or are rejected are skipped and
/// counted by reason. Returns false (with a message) only when nothing can be done: a bad
/// folder, an unwritable output directory.
bool runOfflineFusion(const FuseOptions& options, FuseReport* report, std::string* error);

/// stats.json content for `report` and the configuration used.
std::string statsJson(const FuseReport& report, const MapperConfig& config);

}  // namespace stereo_fusion
