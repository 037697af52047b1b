#pragma once
#include <string>
#include <vector>

#include "stereo_fusion/ParameterTable.h"
#include "stereo_fusion/map/ResolutionLevel.h"
#include "stereo_fusion/map/TruncationBand.h"

namespace stereo_fusion {

/// How a measurement's weight is computed (thesis eq. 3.10 and beyond).
enum class WeightMode {
  kConstant,       ///< w = 1 wherever the voxel is inside the truncation band.
  kSteinbruecker,  ///< w = 1 in front of δ, linear fall-off to 0 at Φ behind the surface
                   ///< (eq. 3.10).
  kDepthAware,  ///< Steinbrücker fall-off × (z_ref / z)², the inverse of the z² stereo error growth
                ///< (eq. 3.1).
};

enum class LookupMode {
  kNaive,        ///< Algorithm 1: one octree search per valid pixel (and band block).
  kAccelerated,  ///< Algorithm 2: one search per distinct block per image region.
};

/// How submeshes are coloured for export and publication (thesis §3.6).
enum class TextureMode {
  kOff,      ///< vertex colours only (method A)
  kPatches,  ///< plus one image patch per submesh with per-vertex UVs (method B)
};

/// Every parameter of the mapping core. Defaults here are the single source of truth:
/// config/default.yaml and the table in doc/parameters.md are checked against them by the tests.
struct MapperConfig {
  double voxel_size_m = 0.02;  ///< Edge of a finest-level voxel; a block is 8 voxels wide.
  double truncation_vox =
      4.0;  ///< Φ in voxels of the measurement's level (Φ = truncation_vox · s · voxel_size_m).
  double min_depth_m = 0.1;  ///< Disparities giving a nearer depth are ignored.
  double max_depth_m = 8.0;  ///< Disparities giving a farther depth are ignored.
  LevelMode level_mode =
      LevelMode::kNoise;  ///< Switch depths from the camera's depth error, or the fixed ones below.
  double disparity_noise_px =
      0.15;  ///< σ_d: expected disparity error (1σ) of the source, for LevelMode::kNoise.
  int speckle_max_area_px =
      0;  ///< Disparity blobs of at most this many pixels are rejected (OutlierRejection). 0 = off.
  double speckle_max_diff_px =
      1.0;  ///< Neighbours within this disparity difference belong to one blob.
  int edge_reject_radius_px = 1;     ///< Near side of a depth edge: pixels with a farther neighbour
                                     ///< within this radius are rejected. 0 = off.
  double edge_reject_jump_px = 1.0;  ///< ... farther by more than this disparity.
  bool contradiction_filter = true;  ///< Drop isolated measurements far behind confident surfaces.
  double contradiction_min_weight = 2.0;  ///< A surface is confident from this voxel weight on.
  double contradiction_sigmas = 2.0;      ///< "Far behind": by more than this many σ_z.
  double contradiction_max_share = 0.25;  ///< Kept where more of the 5×5 tiles around are behind.
  LevelThresholds levels;                 ///< eq. 3.2 switch depths for LevelMode::kDepth.
  bool update_allocated_finer_level =
      true;  ///< A measurement also updates the next finer level where a block already holds it
             ///< (never allocates it).
  WeightMode weight_mode = WeightMode::kSteinbruecker;
  double weight_falloff_start_vox = 1.0;  ///< δ of eq. 3.10, in voxels of the measurement's level.
  double depth_weight_reference_m =
      1.0;                    ///< z_ref of the depth-aware weight (w = 1 at this depth).
  double max_weight = 100.0;  ///< Cap on the cumulative weight W so the map can still change.
  bool free_space_carving =
      true;  ///< Blocks seen through (beyond fusion's bands) are updated towards free space.
  double free_space_decay =
      0.2;  ///< Share of a voxel's weight a see-through frame removes before its free-space update.
  int free_space_window_px =
      1;  ///< A voxel is seen through only if every pixel within this radius measures beyond it.
  LookupMode lookup_mode = LookupMode::kAccelerated;
  int lookup_region_px = 16;     ///< Edge of the square image regions of Algorithm 2.
  int histogram_min_points = 4;  ///< Blocks hit by fewer points in a region are dropped; 0 = off.
  int num_threads = 0;           ///< Worker threads including the caller; 0 = all cores.
  bool use_color = true;         ///< Fuse the colour image into per-voxel colour.
  bool mesh_enabled = true;      ///< Re-mesh the changed blocks after every frame.
  double mesh_level_min_coverage = 0.8;  ///< A block meshes at the finest level whose observed area
                                         ///< is ≥ this share of its best level's.
  bool mesh_fill_seams =
      true;  ///< Unobserved face voxels of a block take its coarser levels' values (no seam holes).
  TextureMode texture =
      TextureMode::kOff;  ///< off: vertex colours only; patches: a texture patch per submesh.
  int texture_border_px =
      24;  ///< A frame textures a block only if all its vertices project this far inside the image.
  int texture_max_patch_px =
      64;  ///< Cap on a patch's edge; larger crops are downscaled (bounds texture memory).
  int max_blocks = 0;  ///< Memory budget in blocks (0.3–7 KB each); beyond it the least recently
                       ///< updated are evicted. 0 = unlimited.
  double min_coherent_pixel_share =
      0.5;  ///< A frame whose usable disparities agree with a neighbour less often is rejected
            ///< (DisparityCoherence). 0 = no check.
  int max_lookup_blocks_per_frame = 20000000;  ///< Work bound of the lookup (see the registry)
  int max_new_blocks_per_frame = 50000;  ///< A frame whose bands reach more blocks not yet in the
                                         ///< map is rejected before fusion. 0 = no limit.
  double max_distance_from_camera_m =
      0.0;  ///< Blocks whose centre is farther from the current camera are evicted. 0 = unlimited.
  double max_map_memory_mb = 0.0;    ///< Beyond it blocks are paged out to map_store_path, not
                                     ///< lost. 0 = unlimited (no paging).
  std::string map_store_path;        ///< Folder of the block store; empty: the temporary folder.
  double checkpoint_period_s = 0.0;  ///< > 0: map_store_path/map.sqlite keeps the map, written
                                     ///< every period (what a kill loses). 0: no checkpoints.
  bool resume = false;               ///< Continue the map kept in map_store_path/map.sqlite.
  /// Whether map_store_path/map.sqlite keeps the map (checkpoints or resume).
  bool keepsMapStore() const { return resume || checkpoint_period_s > 0.0; }
  double max_pose_jump_m = 100.0;  ///< A camera more than this from the last fused frame's camera
                                   ///< is rejected. 0 = no check.
  double max_timestamp_gap_s = 3600.0;  ///< A timestamp more than this after the last fused frame's
                                        ///< is rejected. 0 = no check.
  bool require_increasing_timestamps =
      true;  ///< Reject frames whose (non-zero) timestamp is not after the last fused frame's.
  bool planning_enabled =
      true;  ///< Keep the planning layer: seen-free space, occupancy and the ESDF (planning/).
  double esdf_voxel_size_m =
      0.0;  ///< Cell edge of the planning layer; 0 = auto (planningCellSizeM()).
  double esdf_max_distance_m =
      2.0;  ///< Distances are exact up to this; farther cells read "at least this".
  double free_space_unmeasured_range_m =
      0.0;  ///< Rays without a measurement count as free up to this range. 0 = off.
  double occupancy_min_weight =
      2.0;  ///< A TSDF voxel is evidence for the planning layer from this weight on.
  double grid_min_z_m = 0.1;     ///< Height band of the 2D occupancy grid (world z), lower bound.
  double grid_max_z_m = 1.5;     ///< ... upper bound.
  int grid_max_cells = 4194304;  ///< Largest occupancy grid; wider maps give a window of it.

  /// Block edge length in metres.
  double blockSizeM() const { return 8.0 * voxel_size_m; }
  /// Edge of a planning-layer cell: esdf_voxel_size_m, or with 0 the multiple voxel_size_m · n
  /// (n = 1, 2, 4 or 8) nearest in ratio to max(8 cm, range / 128), the range being
  /// max(max_depth_m, free_space_unmeasured_range_m): 4 voxels at 2 cm and 8 at 1 cm indoors
  /// (8 m), 20 cm cells for a 10 cm map out to 25 m.
  double planningCellSizeM() const;
  /// Φ by level, as every stage applies it.
  TruncationBand truncationBand() const { return TruncationBand(voxel_size_m, truncation_vox); }
};

/// All parameters of MapperConfig (ParameterSpec: ParameterTable.h), in the order of
/// config/default.yaml.
const std::vector<ParameterSpec>& mapperParameterSpecs();

/// Sets parameter `name` from its textual value. Returns false with a message naming the
/// parameter (and its range and unit) when the name is unknown, the value does not parse, or it
/// is out of range.
bool setMapperParameter(MapperConfig* config, const std::string& name, const std::string& value,
                        std::string* error);
/// Textual value of parameter `name` (as setMapperParameter accepts it); empty if unknown.
std::string getMapperParameter(const MapperConfig& config, const std::string& name);

/// Checks ranges and cross-parameter rules. Returns one message per violation (empty = valid).
std::vector<std::string> validateMapperConfig(const MapperConfig& config);

}  // namespace stereo_fusion
