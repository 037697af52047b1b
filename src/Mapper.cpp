#include "stereo_fusion/Mapper.h"

#include <stdexcept>

#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace {
const MapperConfig& checked(const MapperConfig& config) {
  const std::vector<std::string> errors = validateMapperConfig(config);
  if (!errors.empty()) {
    std::string message = "invalid stereo_fusion configuration:";
    for (const std::string& e : errors) message += "\n  - " + e;
    throw std::invalid_argument(message);
  }
  return config;
}
}  // namespace

Mapper::Mapper(const MapperConfig& config)
    : config_(checked(config)),
      pool_(config_.num_threads),
      octree_(config_.blockSizeM()),
      lookup_(config_, &pool_),
      fuser_(config_, &pool_),
      mesh_store_(MeshingParams{config_.voxel_size_m, config_.truncation_vox,
                                config_.mesh_level_min_coverage}),
      texture_store_(TextureParams{config_.texture_border_px, config_.texture_max_patch_px,
                                   config_.voxel_size_m, config_.truncation_vox}) {}

IntegrationResult Mapper::integrate(const StereoFrame& frame) {
  IntegrationResult result;
  result.error = validateFrame(frame, config_.blockSizeM());
  if (!result.error.empty()) return result;
  result.accepted = true;
  ++frames_integrated_;

  Timer lookup_timer;
  result.lookup = lookup_.run(frame, &octree_, &queue_);
  result.lookup_ms = lookup_timer.elapsedMs();

  Timer fusion_timer;
  result.fusion = fuser_.fuse(frame, octree_, queue_, frames_integrated_, &updated_);
  result.fusion_ms = fusion_timer.elapsedMs();

  result.updated_blocks.reserve(updated_.size());
  for (const VoxelBlock* block : updated_) result.updated_blocks.push_back(block->key);
  if (config_.mesh_enabled) {
    result.mesh = mesh_store_.update(octree_, result.updated_blocks, &pool_);
    if (config_.texture == TextureMode::kPatches)
      result.texture = texture_store_.update(mesh_store_, result.mesh, frame, frames_integrated_, &pool_);
  }
  return result;
}

MeshChanges Mapper::rebuildMesh() {
  MeshChanges changes = mesh_store_.rebuild(octree_, &pool_);
  // No frame at hand: the stored patches are re-projected onto the rebuilt submeshes.
  if (config_.texture == TextureMode::kPatches) texture_store_.reprojectAll(mesh_store_);
  return changes;
}

void Mapper::reset() {
  octree_.clear();
  mesh_store_.clear();
  texture_store_.clear();
  frames_integrated_ = 0;
}

}  // namespace stereo_fusion
