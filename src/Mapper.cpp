#include "stereo_fusion/Mapper.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "stereo_fusion/map/RegionClearing.h"
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
      stages_(stageConfigs(config_)),
      pool_(config_.num_threads),
      octree_(config_.blockSizeM()),
      pipeline_(stages_.pipeline, &pool_),
      eviction_consumer_(map_changes_.subscribe("eviction")) {
  mesh_ = &addLayer(std::make_unique<MeshLayer>(stages_.mesh, &pool_));
  if (stages_.planning_enabled)
    planning_ = &addLayer(std::make_unique<PlanningLayer>(stages_.planning, &pool_));
}

void Mapper::registerLayer(std::unique_ptr<MapLayer> layer) {
  const BlockChangeLog::Consumer consumer = map_changes_.subscribe(layer->name());
  if (octree_.blockCount() > 0) layer->rebuild(octree_);  // the map so far
  layers_.push_back(LayerSlot{std::move(layer), consumer});
}

BlockChangeLog::Consumer Mapper::consumerOf(const MapLayer& layer) const {
  for (const LayerSlot& slot : layers_)
    if (slot.layer.get() == &layer) return slot.consumer;
  throw std::logic_error(std::string("layer '") + layer.name() + "' is not registered");
}

void Mapper::updateLayer(MapLayer& layer) {
  layer.update(octree_, map_changes_.take(consumerOf(layer)));
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
  if (!pipeline_.run(frame, &octree_, &stage, &result, &edit_)) return result;
  ++frames_integrated_;
  stage.enter(MapperStage::kFusion);
  applyEdit(frame, &result);
  tellLayers(frame, &stage, &result);
  if (mesh_timing == MeshTiming::kNow) {
    MeshPass pass = updateMesh();
    result.mesh = std::move(pass.mesh);
    result.texture = pass.texture;
  }
  return result;
}

void Mapper::applyEdit(const StereoFrame& frame, IntegrationResult* result) {
  Timer insert_timer;
  voxel_bytes_ += edit_.level_bytes_allocated;
  result->updated_blocks.swap(edit_.updated);
  map_changes_.recordUpdated(result->updated_blocks);
  // The blocks the frame created join the map now, in key order (allocation kept apart from the
  // update: only blocks that hold an update are ever allocated), each reported as it is placed,
  // so that no block is in the map without its stages knowing.
  if (!edit_.created.empty()) {
    const size_t existing = result->updated_blocks.size();
    for (std::unique_ptr<VoxelBlock>& block : edit_.created) {
      const BlockKey key = block->key;
      if (octree_.insert(std::move(block)) == nullptr) continue;
      map_changes_.recordUpdated({key});
      result->updated_blocks.push_back(key);
    }
    std::inplace_merge(result->updated_blocks.begin(), result->updated_blocks.begin() + existing,
                       result->updated_blocks.end());
    edit_.created.clear();
  }
  result->fusion_ms += insert_timer.elapsedMs();

  // Memory bound, between fusion and the layers: nothing else touches the octree now.
  StageScope stage(monitor_, MapperStage::kEviction);
  eviction_.recordUpdates(octree_, map_changes_.take(eviction_consumer_).updated,
                          frames_integrated_);
  result->evicted_blocks =
      eviction_.select(octree_, frame.T_world_camera.translation(), stages_.eviction);
  if (result->evicted_blocks.empty()) return;
  for (const BlockKey& key : result->evicted_blocks)
    if (const VoxelBlock* block = octree_.find(key)) voxel_bytes_ -= block->voxelBytes();
  blocks_evicted_ += octree_.erase(result->evicted_blocks);
  map_changes_.recordErased(result->evicted_blocks);
  std::vector<BlockKey> kept;
  std::set_difference(result->updated_blocks.begin(), result->updated_blocks.end(),
                      result->evicted_blocks.begin(), result->evicted_blocks.end(),
                      std::back_inserter(kept));
  result->updated_blocks.swap(kept);
}

void Mapper::tellLayers(const StereoFrame& frame, StageScope* stage, IntegrationResult* result) {
  stage->enter(MapperStage::kFreeSpace);
  Timer hooks_timer;
  const LayerFrame layer_frame{frame, pipeline_.measurements(), frames_integrated_};
  for (LayerSlot& slot : layers_) slot.layer->onFrame(layer_frame);
  if (planning_) result->free_space = planning_->frameFreeSpace();
  result->free_space_ms = hooks_timer.elapsedMs();
  // A layer whose caller never updates it must not make the map log grow without bound: past
  // a few changes per block of the map, its update runs here.
  const size_t bound = std::max<size_t>(kMaxPendingLayerChanges, 4 * octree_.blockCount());
  for (LayerSlot& slot : layers_) {
    if (!slot.layer->catchesUpItself() || map_changes_.pending(slot.consumer) <= bound) continue;
    StageScope layer_stage(monitor_, MapperStage::kPlanning);
    Timer timer;
    slot.layer->update(octree_, map_changes_.take(slot.consumer));
    result->planning_catch_up = true;
    result->planning_catch_up_ms += timer.elapsedMs();
  }
}

PlanningPass Mapper::updatePlanning() {
  StageScope stage(monitor_, MapperStage::kPlanning);
  std::optional<PlanningMap::PendingUpdate> pending = beginPlanningUpdate();
  return pending ? finishPlanningUpdate(std::move(*pending)) : PlanningPass{};
}

std::optional<PlanningMap::PendingUpdate> Mapper::beginPlanningUpdate() {
  if (!planning_) return std::nullopt;
  StageScope stage(monitor_, MapperStage::kPlanning);
  return planning_->begin(octree_, map_changes_.take(consumerOf(*planning_)));
}

PlanningPass Mapper::finishPlanningUpdate(
    PlanningMap::PendingUpdate pending,
    const std::function<void(const PlanningPass&)>& before_end) {
  // No StageScope: the monitor follows the map lock's holder, and this half may run without it.
  return planning_->finish(std::move(pending), before_end);
}

PlanningPass Mapper::rebuildPlanning() {
  if (!planning_) return PlanningPass{};
  StageScope stage(monitor_, MapperStage::kPlanning);
  map_changes_.take(consumerOf(*planning_));  // the rebuild covers them
  return planning_->rebuildTimed(octree_);
}

MeshPass Mapper::updateMesh() {
  StageScope stage(monitor_, MapperStage::kMeshing);
  return mesh_->updateMesh(octree_, map_changes_.take(consumerOf(*mesh_)), &stage);
}

size_t Mapper::blocksAwaitingMesh() const { return map_changes_.pending(consumerOf(*mesh_)); }

size_t Mapper::memoryBytes() const {
  const BlockOctree::MemoryUse use = octree_.memoryUse(/*with_levels=*/false);
  return use.total() + voxel_bytes_;
}

GridWindow Mapper::occupancyGridWindow() const {
  GridWindow w;
  w.max_cells = config_.grid_max_cells;
  if (lastCameraPositionM()) w.centre_m = lastCameraPositionM()->head<2>();
  return w;
}

MeshChanges Mapper::rebuildMesh() {
  StageScope stage(monitor_, MapperStage::kMeshing);
  map_changes_.take(consumerOf(*mesh_));  // the rebuild covers them
  return mesh_->rebuildMesh(octree_);
}

bool Mapper::saveMap(const std::string& path, std::string* error) const {
  std::vector<uint8_t> bytes = encodeMap();
  return writeMapFileBytes(path, &bytes, error);
}

std::vector<uint8_t> Mapper::encodeMap() const {
  MapFileInfo sections;
  for (const LayerSlot& slot : layers_) slot.layer->encode(&sections);
  return encodeMapFileUnsealed(
      octree_, config_, frames_integrated_,
      [this](const VoxelBlock& block) { return eviction_.lastUpdateFrame(block); },
      sections.free_space);
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
  pipeline_.forget();
  voxel_bytes_ = octree_.memoryUse().voxelBytes();
  for (LayerSlot& slot : layers_) slot.layer->adopt(octree_, info);
  return mesh_->adopted();
}

ClearResult Mapper::clearRegion(const MapRegion& region, MeshTiming mesh_timing) {
  StageScope stage(monitor_, MapperStage::kClear);
  ClearResult result;
  result.error = region.validate();
  if (!result.error.empty()) return result;
  result.accepted = true;
  Timer timer;
  // What the layers keep of the region beside the TSDF goes now (the planning layer's
  // seen-free cells); their TSDF-derived part follows through the map log.
  for (LayerSlot& slot : layers_) slot.layer->clearRegion(region);
  const RegionClearing clearing = clearRegionVoxels(region, &octree_);
  result.blocks_visited = clearing.blocks_visited;
  result.blocks_changed = clearing.changed.size();
  result.voxels_cleared = clearing.voxels_cleared;
  voxel_bytes_ -= clearing.bytes_freed;
  if (!clearing.emptied.empty()) result.blocks_erased = octree_.erase(clearing.emptied);
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
  octree_.clear();
  voxel_bytes_ = 0;
  eviction_.clear();
  map_changes_.clear();
  for (LayerSlot& slot : layers_) slot.layer->reset();
  frames_integrated_ = 0;
  blocks_evicted_ = 0;
  pipeline_.forget();
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
