// The map host's paging (max_map_memory_mb): blocks beyond the cap go to the BlockStore with
// their layers' parts and come back before anything reaches them. See Mapper.h for the invariant.
#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <unordered_set>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/paging/BlockPage.h"
#include "stereo_fusion/paging/FrameReach.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace {
/// Gives the pages of the heap a page-out freed back to the system: the blocks' small
/// allocations leave holes glibc keeps otherwise, and the process would stay as large as its
/// largest map (the cap bounds what is resident, not only what is allocated).
void returnFreedMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}
}  // namespace

void Mapper::openStore() {
  const PagingConfig& paging = stages_.paging;
  std::string error;
  store_ = BlockStore::openPrivate(
      paging.store_path, BlockStoreIdentity{paging.voxel_size_m, paging.truncation_vox}, &error);
  if (!store_) throw std::runtime_error("max_map_memory_mb needs a block store: " + error);
  std::unique_ptr<BlockStore> writing = BlockStore::open(
      store_->file(), BlockStoreIdentity{paging.voxel_size_m, paging.truncation_vox}, &error);
  if (!writing) throw std::runtime_error("max_map_memory_mb needs a block store: " + error);
  writer_ = std::make_unique<PageWriter>(std::move(writing));
}

size_t Mapper::mapMemoryBytes() const {
  size_t bytes = memoryBytes() + mesh_->memoryBytes();
  if (planning_) bytes += planning_->map().freeSpaceBytes() + planning_->map().esdfBytes();
  return bytes;
}

Mapper::PageState& Mapper::pageState(const VoxelBlock& block) {
  page_state_.fit(octree_);
  return page_state_[block];
}

uint64_t Mapper::lastUseFrame(const VoxelBlock& block) const {
  const uint64_t updated = eviction_.lastUpdateFrame(block);
  const uint64_t paged_in = block.row < page_state_.size() ? page_state_[block].paged_in_frame : 0;
  return std::max(updated, paged_in);
}

void Mapper::pageInReach(const StereoFrame& frame) {
  if (!validateFrame(frame, octree_.blockSize()).empty()) return;
  const PagingConfig& paging = stages_.paging;
  last_reach_.emplace(frame, paging.max_depth_m, paging.band_m, paging.unmeasured_m,
                      octree_.blockSize());
  if (paged_.empty()) return;
  std::vector<BlockKey> keys;
  paged_.collect([&](const Eigen::Vector3d& lo,
                     const Eigen::Vector3d& hi) { return last_reach_->mayReach(lo, hi); },
                 &keys);
  pageIn(keys);
}

void Mapper::pageInAround(const std::vector<BlockKey>& keys) {
  std::vector<BlockKey> near;
  paged_.collectAround(keys, &near);
  pageIn(near);
}

void Mapper::pageInAll() { pageIn(paged_.sortedKeys(), /*in_use=*/false); }

void Mapper::pageLost(const BlockKey& key, const std::string& why) {
  ++paging_stats_.pages_unreadable;
  paging_stats_.error = "block (" + std::to_string(key.x) + ", " + std::to_string(key.y) + ", " +
                        std::to_string(key.z) + ") lost: " + why;
}

Mapper::Placed Mapper::placePage(const BlockKey& key, const uint8_t* data, size_t size,
                                 std::string* error) {
  ByteReader reader(data, size);
  uint64_t last_update_frame = 0;
  std::unique_ptr<VoxelBlock> block = readPageHead(&reader, key, &last_update_frame, error);
  if (!block) return Placed::kLost;
  const size_t block_voxel_bytes = block->voxelBytes();
  VoxelBlock* placed = octree_.insert(std::move(block));
  if (placed == nullptr) {  // cannot happen: a paged-out key has no block in memory
    *error = "a block of the same key is in memory";
    return Placed::kLost;
  }
  voxel_bytes_ += block_voxel_bytes;
  eviction_.setLastUpdateFrame(octree_, *placed, last_update_frame);
  bool layers_read = reader.get<uint32_t>() == layers_.size();
  for (LayerSlot& slot : layers_) {
    const uint64_t part_bytes = reader.get<uint64_t>();
    if (!layers_read || !reader.ok() || part_bytes > reader.remaining()) {
      layers_read = false;
      break;
    }
    ByteReader part(reader.position(), part_bytes);
    reader.skip(part_bytes);
    layers_read = slot.layer->pageIn(octree_, *placed, &part);
    if (!layers_read) break;
  }
  if (layers_read) return Placed::kWhole;
  *error = "its layers' part of the page is unreadable; re-derived from its voxels";
  return Placed::kVoxelsOnly;
}

void Mapper::encodePage(const VoxelBlock& block, uint64_t last_update_frame,
                        std::vector<uint8_t>* bytes) const {
  ByteWriter page(bytes);
  writePageHead(block, last_update_frame, &page);
  page.put<uint32_t>(static_cast<uint32_t>(layers_.size()));
  for (const LayerSlot& slot : layers_) {
    const size_t at = page.size();
    page.put<uint64_t>(0);
    slot.layer->savePart(block.key, &page);
    const uint64_t part_bytes = page.size() - at - sizeof(uint64_t);
    std::memcpy(page.buffer().data() + at, &part_bytes, sizeof(part_bytes));
  }
}

void Mapper::pageIn(const std::vector<BlockKey>& keys, bool in_use) {
  if (keys.empty() || paged_.empty()) return;
  Timer timer;
  std::vector<uint8_t> page;
  size_t brought = 0;
  writer_->releaseWritten();
  BlockStore::ReadBatch batch(store_.get());
  for (const BlockKey& key : keys) {
    if (!paged_.remove(key)) continue;
    std::string error;
    if (!readPage(key, &page, &batch, &error)) {
      pageLost(key, error.empty() ? "its page is missing from " + store_->file() : error);
      continue;
    }
    paging_stats_.bytes_read += page.size();
    const Placed placed = placePage(key, page.data(), page.size(), &error);
    if (placed == Placed::kLost) {
      pageLost(key, error);
      continue;
    }
    PageState& state = pageState(*octree_.find(key));
    state.paged_in_frame = in_use ? frames_integrated_ : 0;
    state.page_current = placed == Placed::kWhole;
    if (placed == Placed::kVoxelsOnly) {
      // The voxels came back but not the layers' parts: the block is treated as changed, so
      // the layers rebuild their part from it.
      pageLost(key, error);
      map_changes_.recordUpdated({key});
    }
    ++brought;
  }
  paging_stats_.blocks_paged_in += brought;
  const double ms = timer.elapsedMs();
  paging_stats_.page_in_ms += ms;
  paging_stats_.page_in_max_ms = std::max(paging_stats_.page_in_max_ms, ms);
}

void Mapper::pageOutOverCap(PageOutWhen when) {
  noteStoreChanges();  // before the stores' mesh consumer could keep blocks in
  recoverRefusedPages();
  if (!store_ || paging_stats_.stopped) return;
  const size_t cap = stages_.paging.max_map_memory_bytes;
  const size_t bytes = mapMemoryBytes();
  if (bytes <= cap) return;
  Timer timer;
  const size_t to_free =
      bytes - cap + static_cast<size_t>(PagingConfig::kHysteresis * static_cast<double>(cap));
  std::vector<BlockKey> keys;
  std::vector<uint64_t> frames;
  // Blocks a lagging layer (the planning layer between its updates) has not caught up with
  // stay if they can; if not, they go too and come back before its update (takeChanges()).
  if (selectPageOut(to_free, /*keep_lagging=*/true, when, &keys, &frames) < to_free)
    selectPageOut(to_free, /*keep_lagging=*/false, when, &keys, &frames);
  if (keys.empty()) return;
  // The pages, in key order (neighbours lie together in the store), handed to the writer in
  // slices so a pass holds no more than a slice of encoded pages beyond the writer's backlog.
  std::vector<size_t> order(keys.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return keys[a] < keys[b]; });
  const size_t slice_bytes = PagingConfig::maxWriterBacklogBytes(cap) / 4;
  std::vector<BlockKey> leaving, written_keys;
  std::vector<PageWriter::Page> pages;
  size_t written = 0, slice = 0;
  const auto handOver = [&] {
    octree_.erase(leaving);
    leaving.clear();
    if (!written_keys.empty()) writer_->write(std::move(written_keys), std::move(pages));
    written_keys.clear();
    pages.clear();
    slice = 0;
    // What the store wrote since leaves memory now (no read snapshot is open here), and a
    // writer that falls behind makes the frame wait: the pages it holds are memory beyond
    // the cap.
    writer_->releaseWritten();
    if (writer_->pendingBytes() > PagingConfig::maxWriterBacklogBytes(cap)) {
      writer_->flush();
      writer_->releaseWritten();
      ++paging_stats_.writer_waits;
    }
  };
  for (const size_t i : order) {
    const BlockKey& key = keys[i];
    const VoxelBlock& block = *octree_.find(key);
    const bool has_submesh = mesh_->store().submeshes().count(key) > 0;
    if (pageState(block).page_current) {
      ++paging_stats_.pages_kept;  // the store holds this very page: nothing to write
    } else {
      auto bytes = std::make_shared<std::vector<uint8_t>>();
      encodePage(block, frames[i], bytes.get());
      written += bytes->size();
      slice += bytes->size();
      written_keys.push_back(key);
      pages.push_back(std::move(bytes));
    }
    for (LayerSlot& slot : layers_) slot.layer->pageOut(key);
    voxel_bytes_ -= block.voxelBytes();
    paged_.add(key, PagedBlocks::Entry{frames[i], has_submesh});
    leaving.push_back(key);
    if (slice >= slice_bytes) handOver();
  }
  handOver();
  // Before a frame, what was freed is soon taken again by the frame's new blocks.
  if (when == PageOutWhen::kAfter) returnFreedMemory();
  paging_stats_.blocks_paged_out += keys.size();
  paging_stats_.bytes_written += written;
  ++paging_stats_.page_out_passes;
  paging_stats_.page_out_ms += timer.elapsedMs();
}

void Mapper::recoverRefusedPages() {
  std::vector<BlockKey> keys;
  std::string error;
  if (!writer_ || !writer_->failedKeys(&keys, &error)) return;
  // A full disk: paging stops and the map comes back whole into memory, from the pages the
  // store refused.
  std::sort(keys.begin(), keys.end());
  pageIn(keys);
  // Blocks that came back from one of those pages before (page_current) have none in the
  // store either.
  for (const BlockKey& key : keys)
    if (const VoxelBlock* block = octree_.find(key)) pageState(*block).page_current = false;
  writer_->forgetFailed();
  paging_stats_.stopped = true;
  paging_stats_.error = "paging stopped, the map stays in memory: " + error;
}

void Mapper::flushPaging() {
  if (!writer_) return;
  writer_->flush();
  recoverRefusedPages();
}

size_t Mapper::selectPageOut(size_t to_free, bool keep_lagging, PageOutWhen when,
                             std::vector<BlockKey>* keys, std::vector<uint64_t>* frames) const {
  keys->clear();
  frames->clear();
  // What must stay: every block within one block of a change the mesh has not taken (a caller
  // meshes when it likes and the mesh pass reads them; with `keep_lagging`, of any layer's
  // change) and every submesh a consumer of the mesh's changes has not taken.
  std::vector<BlockKey> pending;
  for (const LayerSlot& slot : layers_)
    if (keep_lagging || !slot.layer->catchesUpItself())
      map_changes_.appendPending(slot.consumer, &pending);
  std::unordered_set<BlockKey, BlockKeyHash> stay;
  for (const BlockKey& key : pending)
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) stay.insert(key.offset(dx, dy, dz));
  pending.clear();
  mesh_->appendPendingMeshChanges(&pending);
  stay.insert(pending.begin(), pending.end());

  const Eigen::Vector3d camera = lastCameraPositionM().value_or(Eigen::Vector3d::Zero());
  const Eigen::Vector3d half_block = Eigen::Vector3d::Constant(0.5 * octree_.blockSize());
  std::vector<LeaveCandidate> candidates;
  candidates.reserve(octree_.blockCount());
  for (const VoxelBlock* block : octree_.blocks())
    if (!stay.count(block->key))
      candidates.push_back({lastUseFrame(*block),
                            (octree_.blockOrigin(block->key) + half_block - camera).norm(),
                            block->key});
  // Only the first few leave: order those (twice the blocks of an average size that free
  // `to_free`), and the rest only if they do not suffice.
  const size_t average_bytes = mapMemoryBytes() / std::max<size_t>(1, octree_.blockCount());
  size_t ordered =
      std::min(candidates.size(), 2 * to_free / std::max<size_t>(1, average_bytes) + 64);
  std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(ordered),
                    candidates.end(), leavesFirst);
  size_t freed = 0;
  const auto take = [&](const BlockKey& key) {
    const VoxelBlock* block = octree_.find(key);
    freed += sizeof(VoxelBlock) + block->voxelBytes() + mesh_->blockBytes(key);
    keys->push_back(key);
    frames->push_back(eviction_.lastUpdateFrame(*block));
  };
  // Blocks in the last frame's reach go last: the next frame would bring them back.
  std::vector<BlockKey> in_reach;
  for (size_t n = 0; n < candidates.size() && freed < to_free; ++n) {
    if (n == ordered) {
      std::sort(candidates.begin() + static_cast<std::ptrdiff_t>(n), candidates.end(), leavesFirst);
      ordered = candidates.size();
    }
    const BlockKey& key = candidates[n].key;
    const Eigen::Vector3d lo(key.x, key.y, key.z);
    if (last_reach_ && last_reach_->mayReach(lo, lo + Eigen::Vector3d::Ones()))
      in_reach.push_back(key);
    else
      take(key);
  }
  if (when == PageOutWhen::kAfter)
    for (size_t n = 0; n < in_reach.size() && freed < to_free; ++n) take(in_reach[n]);
  return freed;
}

BlockChangeLog::Changes Mapper::takeChanges(BlockChangeLog::Consumer consumer) {
  if (!paged_.empty()) {
    std::vector<BlockKey> pending;
    map_changes_.appendPending(consumer, &pending);
    std::sort(pending.begin(), pending.end());
    pending.erase(std::unique(pending.begin(), pending.end()), pending.end());
    pageInAround(pending);
  }
  return map_changes_.take(consumer);
}

bool Mapper::readPage(const BlockKey& key, std::vector<uint8_t>* page,
                      BlockStore::ReadBatch* /*batch*/, std::string* error) const {
  // The writer keeps every page the store holds beyond `batch`'s snapshot (it was released
  // before the snapshot began): one of the two has the newest page.
  if (const PageWriter::Page pending = writer_->find(key)) {
    *page = *pending;
    return true;
  }
  return store_->read(key, page, error);
}

void Mapper::forgetPages() {
  paging_stats_ = PagingStats();
  if (!store_) return;
  writer_->flush();
  writer_->forgetFailed();
  paged_.clear();
  page_state_.clear();
  last_reach_.reset();
  std::string error;
  if (!store_->clear(&error)) paging_stats_.error = error;
}

Mapper::PagedMeshParts Mapper::pagedMeshParts(const std::vector<BlockKey>* only) const {
  PagedMeshParts parts;
  if (paged_.empty()) return parts;
  size_t mesh_slot = 0;
  while (layers_[mesh_slot].layer.get() != mesh_) ++mesh_slot;
  std::vector<BlockKey> keys;
  if (only == nullptr) {
    keys = paged_.sortedKeys();
  } else {
    for (const BlockKey& key : *only)
      if (paged_.contains(key)) keys.push_back(key);
  }
  std::vector<uint8_t> page;
  writer_->releaseWritten();
  BlockStore::ReadBatch batch(store_.get());
  for (const BlockKey& key : keys) {
    std::string error;
    if (!readPage(key, &page, &batch, &error)) continue;
    ByteReader reader(page.data(), page.size());
    skipPageHead(&reader);
    reader.get<uint32_t>();
    for (size_t slot = 0; slot < mesh_slot; ++slot) reader.skip(reader.get<uint64_t>());
    const uint64_t part_bytes = reader.get<uint64_t>();
    if (!reader.ok() || part_bytes > reader.remaining()) continue;
    ByteReader part(reader.position(), part_bytes);
    SubMesh mesh;
    TexturePatch patch;
    if (!MeshLayer::pagedParts(&part, &mesh, &patch)) continue;
    if (!mesh.empty()) parts.submeshes.emplace(key, std::move(mesh));
    if (!patch.image_rgb.empty()) parts.patches.emplace(key, std::move(patch));
  }
  return parts;
}

std::vector<BlockKey> Mapper::submeshKeys() const {
  std::vector<BlockKey> keys;
  keys.reserve(mesh_->store().submeshes().size());
  for (const auto& [key, mesh] : mesh_->store().submeshes()) keys.push_back(key);
  for (const auto& [key, entry] : paged_.entries())
    if (entry.has_submesh) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  return keys;
}

Mapper::PagedMeshParts Mapper::wholeMesh() const {
  PagedMeshParts all = pagedMeshParts();
  all.submeshes.insert(mesh_->store().submeshes().begin(), mesh_->store().submeshes().end());
  all.patches.insert(textures().patches().begin(), textures().patches().end());
  return all;
}

TriangleMesh Mapper::extractMesh() const {
  std::vector<const SubMesh*> submeshes;
  for (const auto& [key, mesh] : mesh_->store().submeshes()) submeshes.push_back(&mesh);
  const PagedMeshParts paged = pagedMeshParts();
  for (const auto& [key, mesh] : paged.submeshes) submeshes.push_back(&mesh);
  return weldSubmeshes(std::move(submeshes));
}

}  // namespace stereo_fusion
