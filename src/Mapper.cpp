#include "stereo_fusion/Mapper.h"

#include <algorithm>
#include <functional>
#include <iterator>
#include <stdexcept>

#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/map/EvictionPolicy.h"
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
                                   config_.voxel_size_m, config_.truncation_vox}),
      gate_(config_.max_pose_jump_m, config_.require_increasing_timestamps) {}

IntegrationResult Mapper::integrate(const StereoFrame& frame) {
  IntegrationResult result;
  result.error = validateFrame(frame, config_.blockSizeM());
  if (!result.error.empty()) {
    result.reason = RejectReason::kInvalidFrame;
    return result;
  }
  result.reason = gate_.check(frame, &result.error);
  if (result.reason != RejectReason::kNone) return result;
  gate_.accepted(frame);
  result.accepted = true;
  ++frames_integrated_;

  Timer lookup_timer;
  result.lookup = lookup_.run(frame, &octree_, &queue_, &missing_);
  result.lookup_ms = lookup_timer.elapsedMs();

  Timer fusion_timer;
  // Mesh levels are refreshed by the fusion workers while each block is still in cache.
  std::function<void(VoxelBlock*)> refresh_level;
  if (config_.mesh_enabled)
    refresh_level = [coverage = config_.mesh_level_min_coverage](VoxelBlock* b) { refreshMeshLevel(b, coverage); };
  result.fusion =
      fuser_.fuse(frame, octree_, queue_, missing_, frames_integrated_, &updated_, &created_, refresh_level);
  // The blocks the frame created join the map now, in key order (allocation kept apart from the
  // update: only blocks that hold an update are ever allocated).
  if (!created_.empty()) {
    const size_t existing = updated_.size();
    for (std::unique_ptr<VoxelBlock>& block : created_)
      if (VoxelBlock* placed = octree_.insert(std::move(block))) updated_.push_back(placed);
    std::inplace_merge(updated_.begin(), updated_.begin() + existing, updated_.end(),
                       [](const VoxelBlock* a, const VoxelBlock* b) { return a->key < b->key; });
  }
  result.lookup.blocks_allocated = result.fusion.blocks_created;
  result.fusion_ms = fusion_timer.elapsedMs();

  result.updated_blocks.reserve(updated_.size());
  for (const VoxelBlock* block : updated_) result.updated_blocks.push_back(block->key);

  // Memory bound, between fusion and meshing: nothing else touches the octree now.
  const EvictionLimits limits{static_cast<size_t>(config_.max_blocks), config_.max_distance_from_camera_m};
  result.evicted_blocks = selectBlocksToEvict(octree_, frame.T_world_camera.translation(), limits);
  if (!result.evicted_blocks.empty()) {
    queue_.clear();  // their pointers dangle after erase
    // The updated blocks that stay go on to meshing (checked before erase frees the others).
    updated_.erase(std::remove_if(updated_.begin(), updated_.end(),
                                  [&](const VoxelBlock* block) {
                                    return std::binary_search(result.evicted_blocks.begin(),
                                                              result.evicted_blocks.end(), block->key);
                                  }),
                   updated_.end());
    blocks_evicted_ += octree_.erase(result.evicted_blocks);
    std::vector<BlockKey> kept;
    std::set_difference(result.updated_blocks.begin(), result.updated_blocks.end(), result.evicted_blocks.begin(),
                        result.evicted_blocks.end(), std::back_inserter(kept));
    result.updated_blocks.swap(kept);
  }
  if (config_.mesh_enabled) {
    result.mesh = mesh_store_.remeshUpdatedBlocks(octree_, updated_, &pool_, result.evicted_blocks);
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

bool Mapper::saveMap(const std::string& path, std::string* error) const {
  std::vector<uint8_t> bytes = encodeMap();
  return writeMapFileBytes(path, &bytes, error);
}

std::vector<uint8_t> Mapper::encodeMap() const {
  return encodeMapFileUnsealed(octree_, config_, frames_integrated_);
}

bool Mapper::loadMap(const std::string& path, MeshChanges* changes, std::string* error) {
  BlockOctree loaded(config_.blockSizeM());
  MapFileInfo info;
  if (!readMapFile(path, config_, &loaded, &info, error)) return false;
  MeshChanges adopted = adoptMap(&loaded, info);  // the old map now lives in `loaded`, freed on return
  if (changes) *changes = std::move(adopted);
  return true;
}

MeshChanges Mapper::adoptMap(BlockOctree* loaded, const MapFileInfo& info) {
  octree_.swap(*loaded);
  queue_.clear();
  missing_.clear();
  updated_.clear();
  // Later frames must count on from the saved ones, so last_update_frame keeps its LRU order.
  frames_integrated_ = info.frames_integrated;
  for (const VoxelBlock* b : octree_.blocks()) frames_integrated_ = std::max(frames_integrated_, b->last_update_frame);
  blocks_evicted_ = 0;
  gate_.reset();
  // The map file holds no texture patches: the loaded map starts with vertex colours.
  texture_store_.clear();
  // A rebuild over the kept store reports the old map's vanished submeshes as removed.
  MeshChanges rebuilt = config_.mesh_enabled ? mesh_store_.rebuild(octree_, &pool_) : MeshChanges{};
  if (!config_.mesh_enabled) mesh_store_.clear();
  return rebuilt;
}

void Mapper::reset() {
  octree_.clear();
  mesh_store_.clear();
  texture_store_.clear();
  frames_integrated_ = 0;
  blocks_evicted_ = 0;
  gate_.reset();
}

}  // namespace stereo_fusion
