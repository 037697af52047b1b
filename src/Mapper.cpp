#include "stereo_fusion/Mapper.h"

#include <algorithm>
#include <cstdio>
#include <functional>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "stereo_fusion/integration/DisparityCoherence.h"
#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/map/RegionClearing.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace {
/// `value` printed with `pattern`, e.g. "%.1f %%".
std::string format(const char* pattern, double value) {
  char text[32];
  std::snprintf(text, sizeof(text), pattern, value);
  return text;
}

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
      lookup_(lookupConfig(config_), &pool_),
      fuser_(fusionConfig(config_), &pool_),
      carver_(carveConfig(config_), &pool_),
      mesh_store_(MeshingParams{config_.voxel_size_m, config_.truncation_vox,
                                config_.mesh_level_min_coverage, config_.mesh_fill_seams}),
      texture_store_(TextureParams{config_.texture_border_px, config_.texture_max_patch_px,
                                   config_.voxel_size_m, config_.truncation_vox}),
      mesh_consumer_(map_changes_.subscribe("mesher")),
      eviction_consumer_(map_changes_.subscribe("eviction")),
      texture_consumer_(
          config_.texture == TextureMode::kPatches
              ? std::optional<BlockChangeLog::Consumer>(mesh_changes_.subscribe("textures"))
              : std::nullopt),
      gate_(FrameGateLimits{config_.max_pose_jump_m, config_.max_timestamp_gap_s,
                            config_.require_increasing_timestamps}) {
  if (config_.planning_enabled) {
    planning_.emplace(PlanningConfig::from(config_), &pool_);
    planning_consumer_ = map_changes_.subscribe("planning");
  }
}

const char* mapperStageName(MapperStage stage) {
  switch (stage) {
    case MapperStage::kIdle: return "idle";
    case MapperStage::kValidate: return "validation";
    case MapperStage::kLookup: return "lookup";
    case MapperStage::kFusion: return "fusion";
    case MapperStage::kCarving: return "carving";
    case MapperStage::kEviction: return "eviction";
    case MapperStage::kFreeSpace: return "free space";
    case MapperStage::kPlanning: return "planning";
    case MapperStage::kMeshing: return "meshing";
    case MapperStage::kTexture: return "texture";
    case MapperStage::kClear: return "clear";
    case MapperStage::kLoad: return "load";
  }
  return "unknown";
}

IntegrationResult Mapper::integrate(const StereoFrame& frame, MeshTiming mesh_timing) {
  StageScope stage(monitor_, MapperStage::kValidate);
  IntegrationResult result;
  result.error = validateFrame(frame, config_.blockSizeM());
  if (!result.error.empty()) {
    result.reason = RejectReason::kInvalidFrame;
    return result;
  }
  std::string gate_message;
  result.reason = gate_.check(frame, &gate_message, &result.reanchored);
  if (result.reason != RejectReason::kNone) result.error = gate_message;
  if (result.reanchored) result.note = gate_message;
  if (result.reason != RejectReason::kNone) return result;

  // A frame the gate passed but the measurements or the lookup refuse is not fused, so the gate
  // does not follow it (no re-anchoring either).
  auto reject_after_gate = [&result](RejectReason reason, std::string error) {
    result.reason = reason;
    result.error = std::move(error);
    result.reanchored = false;
    result.note.clear();
    return result;
  };
  stage.enter(MapperStage::kLookup);
  Timer lookup_timer;
  measurements_.build(frame, config_, &pool_);
  result.disparity_noise_px = measureDisparityNoise(frame.disparity_px, measurements_).sigma_px;
  if (config_.min_coherent_pixel_share > 0.0) {
    const DisparityCoherence coherence =
        measureDisparityCoherence(frame.disparity_px, measurements_, &pool_);
    if (coherence.usable_pixels >= kCoherenceMinUsablePixels &&
        coherence.share() < config_.min_coherent_pixel_share)
      return reject_after_gate(RejectReason::kIncoherentDisparity,
                               "only " + format("%.1f %%", 100.0 * coherence.share()) + " of its " +
                                   std::to_string(coherence.usable_pixels) +
                                   " usable disparities agree within " +
                                   format("%g", kCoherenceTolerancePx) +
                                   " px with a neighbour, less than min_coherent_pixel_share (" +
                                   format("%.1f %%", 100.0 * config_.min_coherent_pixel_share) +
                                   "): a broken matcher or a wrong topic?");
  }
  // After the coherence check: rejection would leave a random frame's few coherent pixels.
  result.rejected = outlier_rejection_.apply(frame.disparity_px, config_, &measurements_, &pool_);
  result.lookup = lookup_.run(frame, measurements_, &octree_, &queue_, &missing_);
  result.lookup_ms = lookup_timer.elapsedMs();
  if (result.lookup.over_work_bound)
    return reject_after_gate(
        RejectReason::kWorkBound,
        "its truncation bands span " + std::to_string(result.lookup.box_blocks) +
            " blocks for the lookup to visit, more than max_lookup_blocks_per_frame (" +
            std::to_string(config_.max_lookup_blocks_per_frame) +
            "): an absurd calibration or depth range?");
  // The lookup only reads the map: a frame over its allocation budget leaves it untouched.
  if (config_.max_new_blocks_per_frame > 0 &&
      missing_.size() > static_cast<size_t>(config_.max_new_blocks_per_frame))
    return reject_after_gate(
        RejectReason::kAllocationBudget,
        "its truncation bands reach " + std::to_string(missing_.size()) +
            " blocks not yet in the map, more than max_new_blocks_per_frame (" +
            std::to_string(config_.max_new_blocks_per_frame) + "): noise or a wrong calibration?");
  gate_.accepted(frame);
  result.accepted = true;
  if (std::isfinite(result.disparity_noise_px)) {
    recent_noise_px_.push_back(result.disparity_noise_px);
    if (recent_noise_px_.size() > kNoiseFrames) recent_noise_px_.pop_front();
  }
  ++frames_integrated_;
  if (texture_consumer_)
    last_frame_ = frame;  // shares the images: what a deferred texture pass projects into

  if (config_.contradiction_filter) {
    Timer contradiction_timer;
    // Never finer than configured; noisier where the frame itself measures more.
    const double sigma_d_px = std::isfinite(result.disparity_noise_px)
                                  ? std::max(config_.disparity_noise_px, result.disparity_noise_px)
                                  : config_.disparity_noise_px;
    result.contradiction =
        contradiction_.apply(frame, octree_, queue_, config_, sigma_d_px, &pool_, &measurements_);
    result.contradiction_ms = contradiction_timer.elapsedMs();
  }
  stage.enter(MapperStage::kFusion);
  Timer fusion_timer;
  result.fusion =
      fuser_.fuse(frame, measurements_, octree_, queue_, missing_, &updated_, &created_);
  voxel_bytes_ += result.fusion.level_bytes_allocated;
  for (const VoxelBlock* block : updated_) result.updated_blocks.push_back(block->key);
  result.fusion_ms = fusion_timer.elapsedMs();
  if (config_.free_space_carving) {
    // Before the created blocks join the map: they are the frame's own, fusion updated them.
    stage.enter(MapperStage::kCarving);
    Timer carve_timer;
    result.carve = carver_.carve(frame, measurements_, octree_, queue_, &carved_);
    std::vector<BlockKey> keys;
    for (const VoxelBlock* block : carved_) keys.push_back(block->key);
    std::vector<BlockKey> merged;
    std::set_union(result.updated_blocks.begin(), result.updated_blocks.end(), keys.begin(),
                   keys.end(), std::back_inserter(merged));
    result.updated_blocks.swap(merged);
    result.carve_ms = carve_timer.elapsedMs();
  }
  stage.enter(MapperStage::kFusion);
  Timer insert_timer;
  map_changes_.recordUpdated(result.updated_blocks);
  // The blocks the frame created join the map now, in key order (allocation kept apart from the
  // update: only blocks that hold an update are ever allocated), each reported as it is placed,
  // so that no block is in the map without its stages knowing.
  if (!created_.empty()) {
    const size_t existing = result.updated_blocks.size();
    for (std::unique_ptr<VoxelBlock>& block : created_) {
      const BlockKey key = block->key;
      if (octree_.insert(std::move(block)) == nullptr) continue;
      map_changes_.recordUpdated({key});
      result.updated_blocks.push_back(key);
    }
    std::inplace_merge(result.updated_blocks.begin(), result.updated_blocks.begin() + existing,
                       result.updated_blocks.end());
  }
  updated_.clear();  // the stages after fusion work from the change log
  carved_.clear();
  result.fusion_ms += insert_timer.elapsedMs();

  // Memory bound, between fusion and meshing: nothing else touches the octree now.
  stage.enter(MapperStage::kEviction);
  eviction_.recordUpdates(octree_, map_changes_.take(eviction_consumer_).updated,
                          frames_integrated_);
  const EvictionLimits limits{static_cast<size_t>(config_.max_blocks),
                              config_.max_distance_from_camera_m};
  result.evicted_blocks = eviction_.select(octree_, frame.T_world_camera.translation(), limits);
  if (!result.evicted_blocks.empty()) {
    queue_.clear();  // their pointers dangle after erase
    for (const BlockKey& key : result.evicted_blocks)
      if (const VoxelBlock* block = octree_.find(key)) voxel_bytes_ -= block->voxelBytes();
    blocks_evicted_ += octree_.erase(result.evicted_blocks);
    map_changes_.recordErased(result.evicted_blocks);
    std::vector<BlockKey> kept;
    std::set_difference(result.updated_blocks.begin(), result.updated_blocks.end(),
                        result.evicted_blocks.begin(), result.evicted_blocks.end(),
                        std::back_inserter(kept));
    result.updated_blocks.swap(kept);
  }
  if (planning_) {
    stage.enter(MapperStage::kFreeSpace);
    Timer free_space_timer;
    result.free_space = planning_->recordFreeSpace(frame, measurements_);
    if (config_.max_distance_from_camera_m > 0.0)
      planning_->dropFartherThan(frame.T_world_camera.translation(),
                                 config_.max_distance_from_camera_m);
    result.free_space_ms = free_space_timer.elapsedMs();
    // A caller that never updates the planning layer must not make the map log grow without
    // bound: past a few changes per block of the map, the update runs here.
    if (map_changes_.pending(*planning_consumer_) >
        std::max<size_t>(kMaxPendingPlanningChanges, 4 * octree_.blockCount())) {
      result.planning_catch_up = true;
      result.planning_catch_up_ms = updatePlanning().esdf_ms;
    }
  }
  if (mesh_timing == MeshTiming::kNow) {
    MeshPass pass = updateMesh();
    result.mesh = std::move(pass.mesh);
    result.texture = pass.texture;
  }
  return result;
}

PlanningPass Mapper::updatePlanning() {
  StageScope stage(monitor_, MapperStage::kPlanning);
  std::optional<PlanningMap::PendingUpdate> pending = beginPlanningUpdate();
  return pending ? finishPlanningUpdate(std::move(*pending)) : PlanningPass{};
}

std::optional<PlanningMap::PendingUpdate> Mapper::beginPlanningUpdate() {
  if (!planning_) return std::nullopt;
  StageScope stage(monitor_, MapperStage::kPlanning);
  const BlockChangeLog::Changes changes = map_changes_.take(*planning_consumer_);
  return planning_->beginUpdate(octree_, changes.updated, changes.erased);
}

PlanningPass Mapper::finishPlanningUpdate(
    PlanningMap::PendingUpdate pending,
    const std::function<void(const PlanningPass&)>& before_end) {
  // No StageScope: the monitor follows the map lock's holder, and this half may run without it.
  Timer timer;
  PlanningPass pass;
  // Timed up to the update's end proper: adding the frames' kept free space is theirs.
  planning_->finishUpdate(std::move(pending), [&](const PlanningUpdateStats& stats) {
    pass.stats = stats;
    pass.esdf_ms = stats.read_ms + timer.elapsedMs();
    if (before_end) before_end(pass);
  });
  return pass;
}

PlanningPass Mapper::rebuildPlanning() {
  PlanningPass pass;
  if (!planning_) return pass;
  StageScope stage(monitor_, MapperStage::kPlanning);
  Timer timer;
  map_changes_.take(*planning_consumer_);  // the rebuild covers them
  pass.stats = planning_->rebuild(octree_);
  pass.esdf_ms = timer.elapsedMs();
  return pass;
}

MeshPass Mapper::updateMesh() {
  MeshPass pass;
  const BlockChangeLog::Changes changes = map_changes_.take(mesh_consumer_);
  pass.blocks_changed = changes.updated.size() + changes.erased.size();
  if (!config_.mesh_enabled || changes.empty()) return pass;
  StageScope stage(monitor_, MapperStage::kMeshing);
  pass.mesh = mesh_store_.update(octree_, changes.updated, &pool_, changes.erased);
  recordMeshChanges(pass.mesh);
  if (texture_consumer_) {
    stage.enter(MapperStage::kTexture);
    const BlockChangeLog::Changes retexture = mesh_changes_.take(*texture_consumer_);
    MeshChanges submeshes;
    submeshes.changed = retexture.updated;
    submeshes.removed = retexture.erased;
    pass.texture =
        texture_store_.update(mesh_store_, submeshes, last_frame_, frames_integrated_, &pool_);
  }
  return pass;
}

size_t Mapper::blocksAwaitingMesh() const { return map_changes_.pending(mesh_consumer_); }

size_t Mapper::memoryBytes() const {
  const BlockOctree::MemoryUse use = octree_.memoryUse(/*with_levels=*/false);
  return use.total() + voxel_bytes_;
}

void Mapper::recordMeshChanges(const MeshChanges& changes) {
  mesh_changes_.recordUpdated(changes.changed);
  mesh_changes_.recordErased(changes.removed);
}

MeshChanges Mapper::rebuildMesh() {
  StageScope stage(monitor_, MapperStage::kMeshing);
  map_changes_.take(mesh_consumer_);  // the rebuild covers them
  MeshChanges changes = mesh_store_.rebuild(octree_, &pool_);
  recordMeshChanges(changes);
  // No frame at hand: the stored patches are re-projected onto the rebuilt submeshes.
  if (texture_consumer_) {
    mesh_changes_.take(*texture_consumer_);
    texture_store_.reprojectAll(mesh_store_);
  }
  return changes;
}

bool Mapper::saveMap(const std::string& path, std::string* error) const {
  std::vector<uint8_t> bytes = encodeMap();
  return writeMapFileBytes(path, &bytes, error);
}

std::vector<uint8_t> Mapper::encodeMap() const {
  SeenFreeSpace free_space;
  if (planning_) {
    free_space.cell_m = planning_->grid().cell_m;
    free_space.blocks = planning_->seenFree();
  }
  return encodeMapFileUnsealed(
      octree_, config_, frames_integrated_,
      [this](const VoxelBlock& block) { return eviction_.lastUpdateFrame(block); }, free_space);
}

bool Mapper::loadMap(const std::string& path, MeshChanges* changes, std::string* error) {
  BlockOctree loaded(config_.blockSizeM());
  MapFileInfo info;
  if (!readMapFile(path, config_, &loaded, &info, error)) return false;
  MeshChanges adopted =
      adoptMap(&loaded, info);  // the old map now lives in `loaded`, freed on return
  if (changes) *changes = std::move(adopted);
  return true;
}

MeshChanges Mapper::adoptMap(BlockOctree* loaded, const MapFileInfo& info) {
  StageScope stage(monitor_, MapperStage::kLoad);
  octree_.swap(*loaded);
  queue_.clear();
  missing_.clear();
  updated_.clear();
  map_changes_.clear();
  // Later frames must count on from the saved ones, so the eviction order is kept.
  eviction_.clear();
  frames_integrated_ = info.frames_integrated;
  for (const auto& [key, frame] : info.last_update_frames) {
    if (const VoxelBlock* block = octree_.find(key))
      eviction_.setLastUpdateFrame(octree_, *block, frame);
    frames_integrated_ = std::max(frames_integrated_, frame);
  }
  blocks_evicted_ = 0;
  gate_.reset();
  last_frame_ = StereoFrame();
  voxel_bytes_ = octree_.memoryUse().voxelBytes();
  // The map file holds no texture patches: the loaded map starts with vertex colours.
  texture_store_.clear();
  if (planning_) {
    // The file's seen-free cells if they are of this layer's size (else its free space is
    // unknown, as with an older file), then the rest from the TSDF.
    planning_->clear();
    if (info.free_space.cell_m == planning_->grid().cell_m)
      planning_->addSeenFree(info.free_space.blocks);
    planning_->rebuild(octree_);
  }
  // A rebuild over the kept store reports the old map's vanished submeshes as removed.
  MeshChanges rebuilt;
  if (config_.mesh_enabled) {
    rebuilt = mesh_store_.rebuild(octree_, &pool_);
    recordMeshChanges(rebuilt);
  } else {
    mesh_store_.clear();
  }
  if (texture_consumer_) mesh_changes_.take(*texture_consumer_);  // nothing to texture from
  return rebuilt;
}

ClearResult Mapper::clearRegion(const MapRegion& region, MeshTiming mesh_timing) {
  StageScope stage(monitor_, MapperStage::kClear);
  ClearResult result;
  result.error = region.validate();
  if (!result.error.empty()) return result;
  result.accepted = true;
  Timer timer;
  // Its seen-free cells become unknown now; its TSDF cells follow through the map log.
  if (planning_) planning_->clearRegion(region);
  const RegionClearing clearing = clearRegionVoxels(region, &octree_);
  result.blocks_visited = clearing.blocks_visited;
  result.blocks_changed = clearing.changed.size();
  result.voxels_cleared = clearing.voxels_cleared;
  voxel_bytes_ -= clearing.bytes_freed;
  if (!clearing.emptied.empty()) {
    queue_.clear();  // their pointers dangle after erase
    result.blocks_erased = octree_.erase(clearing.emptied);
  }
  // Eviction keeps each block's last update: a cleared block is not "recently updated".
  map_changes_.recordUpdated(clearing.changed);
  map_changes_.recordErased(clearing.emptied);
  map_changes_.take(eviction_consumer_);
  result.clear_ms = timer.elapsedMs();
  if (mesh_timing == MeshTiming::kNow) {
    MeshPass pass = updateMesh();
    result.mesh = std::move(pass.mesh);
    result.texture = pass.texture;
  }
  return result;
}

void Mapper::reset() {
  MeshChanges dropped;
  for (const auto& [key, submesh] : mesh_store_.submeshes()) dropped.removed.push_back(key);
  std::sort(dropped.removed.begin(), dropped.removed.end());
  octree_.clear();
  voxel_bytes_ = 0;
  mesh_store_.clear();
  texture_store_.clear();
  eviction_.clear();
  map_changes_.clear();
  if (planning_) planning_->clear();
  // The mesh's consumers learn that every submesh is gone, after whatever they have not taken.
  recordMeshChanges(dropped);
  if (texture_consumer_) mesh_changes_.take(*texture_consumer_);
  last_frame_ = StereoFrame();
  frames_integrated_ = 0;
  blocks_evicted_ = 0;
  gate_.reset();
}

double Mapper::measuredDisparityNoisePx() const {
  if (recent_noise_px_.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::vector<double> values(recent_noise_px_.begin(), recent_noise_px_.end());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

std::string Mapper::disparityNoiseWarning() const {
  const double measured = measuredDisparityNoisePx();
  const double configured = config_.disparity_noise_px;
  if (!std::isfinite(measured) || !(measured > 1.5 * configured)) return {};
  char text[256];
  std::snprintf(text, sizeof(text),
                "the disparities measure a noise of %.2f px (median of the last %zu frames), "
                "disparity_noise_px is %.2f: set disparity_noise_px to what the source gives "
                "(the contradiction rule already uses the larger of the two)",
                measured, kNoiseFrames, configured);
  return text;
}

}  // namespace stereo_fusion
