#include "stereo_fusion/Mapper.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "stereo_fusion/map/RegionClearing.h"
#include "stereo_fusion/paging/BlockPage.h"
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
  if (stages_.paging.enabled()) openStore();
  mesh_ = &addLayer(std::make_unique<MeshLayer>(stages_.mesh, &pool_));
  if (stages_.planning_enabled)
    planning_ = &addLayer(std::make_unique<PlanningLayer>(stages_.planning, &pool_));
  if (store_) subscribeStoreConsumers();
}

void Mapper::registerLayer(std::unique_ptr<MapLayer> layer) {
  const BlockChangeLog::Consumer consumer = map_changes_.subscribe(layer->name());
  pageInAll();
  if (octree_.blockCount() > 0) layer->rebuild(octree_);  // the map so far
  layers_.push_back(LayerSlot{std::move(layer), consumer});
}

BlockChangeLog::Consumer Mapper::consumerOf(const MapLayer& layer) const {
  for (const LayerSlot& slot : layers_)
    if (slot.layer.get() == &layer) return slot.consumer;
  throw std::logic_error(std::string("layer '") + layer.name() + "' is not registered");
}

void Mapper::updateLayer(MapLayer& layer) { layer.update(octree_, takeChanges(consumerOf(layer))); }

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
  if (store_) {
    const Timer timer;
    const uint64_t before = paging_stats_.blocks_paged_in;
    pageInReach(frame);
    result.blocks_paged_in = paging_stats_.blocks_paged_in - before;
    result.page_in_ms = timer.elapsedMs();
    const uint64_t out_before = paging_stats_.blocks_paged_out;
    pageOutOverCap(PageOutWhen::kBeforeFrame);
    result.blocks_paged_out = paging_stats_.blocks_paged_out - out_before;
    result.paging_ms = timer.elapsedMs();
  }
  if (!pipeline_.run(frame, &octree_, &stage, &result, &edit_)) return result;
  ++frames_integrated_;
  stage.enter(MapperStage::kFusion);
  applyEdit(frame, &result);
  tellLayers(frame, &stage, &result);
  if (mesh_timing == MeshTiming::kNow) {
    MeshPass pass = meshPass();
    result.mesh = std::move(pass.mesh);
    result.texture = pass.texture;
  }
  if (store_) {
    result.map_memory_bytes = mapMemoryBytes();
    paging_stats_.map_memory_peak_bytes =
        std::max(paging_stats_.map_memory_peak_bytes, result.map_memory_bytes);
    const Timer timer;
    const uint64_t before = paging_stats_.blocks_paged_out;
    pageOutOverCap();
    result.blocks_paged_out += paging_stats_.blocks_paged_out - before;
    result.paging_ms += timer.elapsedMs();
  }
  noteStoreChanges();
  if (!checkpoints_in_flight_.empty()) foldCommittedCheckpoints();
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
  result->evicted_blocks = eviction_.select(octree_, frame.T_world_camera.translation(),
                                            stages_.eviction, store_ ? &paged_ : nullptr);
  if (result->evicted_blocks.empty()) return;
  // Evicted blocks leave as from memory, and the mesh re-meshes around them.
  pageInAround(result->evicted_blocks);
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
    slot.layer->update(octree_, takeChanges(slot.consumer));
    result->planning_catch_up = true;
    result->planning_catch_up_ms += timer.elapsedMs();
  }
}

PlanningPass Mapper::updatePlanning() {
  StageScope stage(monitor_, MapperStage::kPlanning);
  std::optional<PlanningMap::PendingUpdate> pending = beginPlanningUpdate();
  if (!pending) return PlanningPass{};
  PlanningPass pass = finishPlanningUpdate(std::move(*pending));
  pageOutOverCap();  // what waited for the planning layer may go now
  return pass;
}

std::optional<PlanningMap::PendingUpdate> Mapper::beginPlanningUpdate() {
  if (!planning_) return std::nullopt;
  StageScope stage(monitor_, MapperStage::kPlanning);
  return planning_->begin(octree_, takeChanges(consumerOf(*planning_)));
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
  pageInAll();
  map_changes_.take(consumerOf(*planning_));  // the rebuild covers them
  return planning_->rebuildTimed(octree_);
}

MeshPass Mapper::updateMesh() {
  MeshPass pass = meshPass();
  pageOutOverCap();
  return pass;
}

MeshPass Mapper::meshPass() {
  StageScope stage(monitor_, MapperStage::kMeshing);
  return mesh_->updateMesh(octree_, takeChanges(consumerOf(*mesh_)), &stage);
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
  pageInAll();
  map_changes_.take(consumerOf(*mesh_));  // the rebuild covers them
  return mesh_->rebuildMesh(octree_);
}

bool Mapper::saveMap(const std::string& path, std::string* error) const {
  MapFileInfo sections;
  for (const LayerSlot& slot : layers_) slot.layer->encode(&sections);
  // Streamed in key order, resident and paged-out blocks merged, one page read at a time: the
  // file never sits whole in memory.
  const std::vector<VoxelBlock*> resident = octree_.blocksSortedByKey();
  const std::vector<BlockKey> paged = paged_.sortedKeys();
  const MapFileBlocks blocks = [&](const std::function<void(const VoxelBlock&, uint64_t)>& sink,
                                   std::string* read_error) {
    std::optional<BlockStore::ReadBatch> batch;
    if (store_) {
      writer_->releaseWritten();
      batch.emplace(store_.get());
    }
    std::vector<uint8_t> page;
    size_t r = 0;
    for (size_t p = 0; p <= paged.size(); ++p) {
      for (; r < resident.size() && (p == paged.size() || resident[r]->key < paged[p]); ++r)
        sink(*resident[r], eviction_.lastUpdateFrame(*resident[r]));
      if (p == paged.size()) break;
      uint64_t frame = 0;
      std::unique_ptr<VoxelBlock> block;
      if (readPage(paged[p], &page, &*batch, read_error)) {
        ByteReader reader(page.data(), page.size());
        block = readPageHead(&reader, paged[p], &frame, read_error);
      }
      if (!block) {
        if (read_error->empty()) *read_error = "a paged-out block's page is missing";
        return false;
      }
      sink(*block, frame);
    }
    return true;
  };
  return writeMapFile(path, config_, frames_integrated_, resident.size() + paged.size(), blocks,
                      sections.free_space, error);
}

std::vector<uint8_t> Mapper::encodeMap() const {
  MapFileInfo sections;
  for (const LayerSlot& slot : layers_) slot.layer->encode(&sections);
  // Paged-out blocks are read back for the file, beside those in memory, in key order.
  std::vector<std::unique_ptr<VoxelBlock>> paged_blocks;
  std::unordered_map<BlockKey, uint64_t, BlockKeyHash> paged_frames;
  std::vector<uint8_t> page;
  std::optional<BlockStore::ReadBatch> batch;
  if (store_) {
    writer_->releaseWritten();
    batch.emplace(store_.get());
  }
  for (const BlockKey& key : paged_.sortedKeys()) {
    std::string error;
    uint64_t frame = 0;
    if (!readPage(key, &page, &*batch, &error)) continue;
    ByteReader reader(page.data(), page.size());
    std::unique_ptr<VoxelBlock> block = readPageHead(&reader, key, &frame, &error);
    if (!block) continue;
    paged_frames[key] = frame;
    paged_blocks.push_back(std::move(block));
  }
  const std::vector<VoxelBlock*> resident = octree_.blocksSortedByKey();
  std::vector<const VoxelBlock*> blocks(resident.begin(), resident.end());
  for (const auto& block : paged_blocks) blocks.push_back(block.get());
  std::inplace_merge(blocks.begin(), blocks.begin() + resident.size(), blocks.end(),
                     [](const VoxelBlock* a, const VoxelBlock* b) { return a->key < b->key; });
  return encodeMapFileUnsealed(
      blocks, config_, frames_integrated_,
      [&](const VoxelBlock& block) {
        return block.row == VoxelBlock::kNoRow ? paged_frames.at(block.key)
                                               : eviction_.lastUpdateFrame(block);
      },
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
  forgetPages();
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
  checkpoint_full_ = true;  // the store's map is not this one any more
  pageOutOverCap();
  return mesh_->adopted();
}

ClearResult Mapper::clearRegion(const MapRegion& region, MeshTiming mesh_timing) {
  StageScope stage(monitor_, MapperStage::kClear);
  ClearResult result;
  result.error = region.validate();
  if (!result.error.empty()) return result;
  result.accepted = true;
  Timer timer;
  // The paged-out blocks the clear changes or re-meshes around (within one block) come back.
  if (!paged_.empty()) {
    const double b = octree_.blockSize();
    std::vector<BlockKey> keys;
    paged_.collect(
        [&](const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
          return region.intersects(Eigen::AlignedBox3d((lo - Eigen::Vector3d::Ones()) * b,
                                                       (hi + Eigen::Vector3d::Ones()) * b));
        },
        &keys);
    pageIn(keys);
  }
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
  forgetPages();
  octree_.clear();
  voxel_bytes_ = 0;
  eviction_.clear();
  map_changes_.clear();
  for (LayerSlot& slot : layers_) slot.layer->reset();
  frames_integrated_ = 0;
  blocks_evicted_ = 0;
  pipeline_.forget();
  checkpoint_full_ = true;  // the store's map is not this one any more
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
