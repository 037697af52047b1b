#include "stereo_fusion/StageConfigs.h"

#include <cmath>

namespace stereo_fusion {

namespace {
LevelConfig levelConfig(const MapperConfig& config) {
  LevelConfig c;
  c.level_mode = config.level_mode;
  c.voxel_size_m = config.voxel_size_m;
  c.disparity_noise_px = config.disparity_noise_px;
  c.levels = config.levels;
  return c;
}

FusionConfig fusionConfig(const MapperConfig& config) {
  FusionConfig c;
  c.voxel_size_m = config.voxel_size_m;
  c.truncation_vox = config.truncation_vox;
  c.weight_mode = config.weight_mode;
  c.weight_falloff_start_vox = config.weight_falloff_start_vox;
  c.depth_weight_reference_m = config.depth_weight_reference_m;
  c.max_weight = config.max_weight;
  c.update_allocated_finer_level = config.update_allocated_finer_level;
  c.free_space_carving = config.free_space_carving;
  c.free_space_decay = config.free_space_decay;
  c.use_color = config.use_color;
  return c;
}

FramePipelineConfig pipelineConfig(const MapperConfig& config) {
  FramePipelineConfig c;
  c.block_size_m = config.blockSizeM();
  c.gate = FrameGateLimits{config.max_pose_jump_m, config.max_timestamp_gap_s,
                           config.require_increasing_timestamps};
  c.measurement.min_depth_m = config.min_depth_m;
  c.measurement.max_depth_m = config.max_depth_m;
  c.measurement.use_color = config.use_color;
  c.measurement.levels = levelConfig(config);
  c.outliers.speckle_max_area_px = config.speckle_max_area_px;
  c.outliers.speckle_max_diff_px = config.speckle_max_diff_px;
  c.outliers.edge_reject_radius_px = config.edge_reject_radius_px;
  c.outliers.edge_reject_jump_px = config.edge_reject_jump_px;
  c.lookup.voxel_size_m = config.voxel_size_m;
  c.lookup.truncation_vox = config.truncation_vox;
  c.lookup.lookup_mode = config.lookup_mode;
  c.lookup.lookup_region_px = config.lookup_region_px;
  c.lookup.histogram_min_points = config.histogram_min_points;
  c.lookup.max_lookup_blocks_per_frame = config.max_lookup_blocks_per_frame;
  c.fusion = fusionConfig(config);
  c.carve.fusion = c.fusion;
  c.carve.free_space_window_px = config.free_space_window_px;
  c.contradiction.voxel_size_m = config.voxel_size_m;
  c.contradiction.contradiction_min_weight = config.contradiction_min_weight;
  c.contradiction.contradiction_sigmas = config.contradiction_sigmas;
  c.contradiction.contradiction_max_share = config.contradiction_max_share;
  c.contradiction_filter = config.contradiction_filter;
  c.free_space_carving = config.free_space_carving;
  c.disparity_noise_px = config.disparity_noise_px;
  c.min_coherent_pixel_share = config.min_coherent_pixel_share;
  c.max_new_blocks_per_frame = config.max_new_blocks_per_frame;
  return c;
}

MeshLayerConfig meshConfig(const MapperConfig& config) {
  MeshLayerConfig c;
  c.enabled = config.mesh_enabled;
  c.textured = config.texture == TextureMode::kPatches;
  c.meshing.voxel_size_m = config.voxel_size_m;
  c.meshing.truncation_vox = config.truncation_vox;
  c.meshing.level_min_coverage = config.mesh_level_min_coverage;
  c.meshing.fill_faces_from_coarser_levels = config.mesh_fill_seams;
  c.texture.border_px = config.texture_border_px;
  c.texture.max_patch_px = config.texture_max_patch_px;
  c.texture.voxel_size_m = config.voxel_size_m;
  c.texture.truncation_vox = config.truncation_vox;
  return c;
}

PlanningLayerConfig planningConfig(const MapperConfig& config) {
  PlanningLayerConfig c;
  PlanningConfig& p = c.planning;
  p.cell_m = config.planningCellSizeM();
  p.voxels_per_cell = static_cast<int>(std::lround(p.cell_m / config.voxel_size_m));
  p.max_distance_m = config.esdf_max_distance_m;
  p.unmeasured_range_m = config.free_space_unmeasured_range_m;
  p.min_weight = static_cast<float>(config.occupancy_min_weight);
  p.band = config.truncationBand();
  c.max_distance_from_camera_m = config.max_distance_from_camera_m;
  return c;
}

PagingConfig pagingConfig(const MapperConfig& config) {
  PagingConfig c;
  c.max_map_memory_bytes = static_cast<size_t>(config.max_map_memory_mb * 1024.0 * 1024.0);
  c.store_path = config.map_store_path;
  c.voxel_size_m = config.voxel_size_m;
  c.truncation_vox = config.truncation_vox;
  c.max_depth_m = config.max_depth_m;
  c.band_m = config.truncationBand().maxM();
  c.unmeasured_m = config.free_space_unmeasured_range_m;
  return c;
}
}  // namespace

StageConfigs stageConfigs(const MapperConfig& config) {
  StageConfigs c;
  c.pipeline = pipelineConfig(config);
  c.eviction =
      EvictionLimits{static_cast<size_t>(config.max_blocks), config.max_distance_from_camera_m};
  c.mesh = meshConfig(config);
  c.planning_enabled = config.planning_enabled;
  c.planning = planningConfig(config);
  c.paging = pagingConfig(config);
  return c;
}

}  // namespace stereo_fusion
