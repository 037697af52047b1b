// The map store (checkpoint_period_s, resume): the map's durable copy, changed only by whole
// checkpoints. See Mapper.h.
#include <algorithm>
#include <filesystem>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace {
constexpr const char* kMapStoreFile = "map.sqlite";
}

Mapper::StoreOpening Mapper::openMapStore(bool resume) {
  StoreOpening out;
  const std::string file = (std::filesystem::path(config_.map_store_path) / kMapStoreFile).string();
  if (map_store_) {
    out.message = file + ": the map store is open already";
    return out;
  }
  std::string error;
  std::unique_ptr<BlockStore> store = BlockStore::open(
      file, BlockStoreIdentity{config_.voxel_size_m, config_.truncation_vox}, &error,
      /*durable=*/true);
  if (!store) {
    out.message = error + " (the store is left as it is; mapping goes on without it)";
    return out;
  }
  std::vector<uint8_t> state_bytes;
  const bool has_state = store->readState(&state_bytes, &error);
  if (!has_state && !error.empty()) {
    out.message = error + " (the store is left as it is; mapping goes on without it)";
    return out;
  }
  if (resume && has_state) {
    if (!resumeFrom(store.get(), &out)) return out;
  } else if (resume) {
    out.message = file + " holds no map yet: a new map starts in it";
  } else {
    out.message = has_state ? file +
                                  ": resume is false, so a new map replaces the one it holds "
                                  "at the first checkpoint"
                            : file + ": a new map starts in it";
  }
  subscribeStoreConsumers();
  // The resumed mesh's changes (every submesh) are no checkpoint's business.
  noteStoreChanges();
  checkpoint_full_ = !out.resumed;
  checkpoint_dirty_.clear();
  checkpoint_stats_ = CheckpointStats();
  checkpoint_stats_.file = file;
  checkpoint_stats_.resumed = out.resumed;
  map_store_ = std::make_unique<PageWriter>(std::move(store));
  out.ok = true;
  return out;
}

bool Mapper::resumeFrom(BlockStore* store, StoreOpening* out) {
  std::vector<uint8_t> state_bytes;
  std::string error;
  CheckpointState state;
  store->readState(&state_bytes, &error);
  if (!decodeCheckpointState(state_bytes, &state, &error)) {
    out->message = store->file() + ": cannot resume: " + error +
                   " (the store is left as it is; mapping goes on without it)";
    return false;
  }
  const std::vector<BlockKey> before = submeshKeys();
  reset();
  std::vector<std::pair<BlockKey, uint64_t>> last_update_frames;
  size_t voxels_only = 0;
  const bool read = store->eachPage(
      [&](const BlockKey& key, const uint8_t* data, size_t size) {
        const Placed placed = placePage(key, data, size, &error);
        if (placed == Placed::kLost) {
          error = "block (" + std::to_string(key.x) + ", " + std::to_string(key.y) + ", " +
                  std::to_string(key.z) + "): " + error;
          return false;
        }
        if (placed == Placed::kVoxelsOnly) ++voxels_only;
        return true;
      },
      &error);
  if (!read) {
    reset();
    out->message = store->file() + ": cannot resume: " + error +
                   " (the store is left as it is; mapping goes on without it)";
    return false;
  }
  MapFileInfo info;
  info.frames_integrated = state.frames_integrated;
  info.free_space = std::move(state.free_space);
  frames_integrated_ = state.frames_integrated;
  map_changes_.clear();
  for (LayerSlot& slot : layers_) slot.layer->resumed(octree_, info);
  // What each consumer of the map log (eviction, the mesh) had not taken at the checkpoint
  // waits for it again.
  for (const CheckpointState::Pending& pending : state.pending)
    for (BlockChangeLog::Consumer c = 0;
         c < static_cast<BlockChangeLog::Consumer>(map_changes_.consumerCount()); ++c)
      if (map_changes_.name(c) == pending.consumer)
        map_changes_.restore(c, BlockChangeLog::Changes{pending.updated, pending.erased});
  out->resumed = true;
  out->owner_note = std::move(state.owner_note);
  out->changes = mesh_->adopted();
  std::set_difference(before.begin(), before.end(), out->changes.changed.begin(),
                      out->changes.changed.end(), std::back_inserter(out->changes.removed));
  out->message = "resumed " + std::to_string(octree_.blockCount()) + " blocks, " +
                 std::to_string(frames_integrated_) + " frames, from " + store->file();
  if (voxels_only > 0)
    out->message += " (" + std::to_string(voxels_only) +
                    " blocks' mesh parts were unreadable: re-meshed from their voxels)";
  pageOutOverCap();
  return true;
}

void Mapper::subscribeStoreConsumers() {
  if (store_map_consumer_) return;
  store_map_consumer_ = map_changes_.subscribe("stores");
  store_mesh_consumer_ = mesh_->subscribe("stores");
}

void Mapper::noteStoreChanges() {
  if (!store_map_consumer_) return;
  const BlockChangeLog::Changes map = map_changes_.take(*store_map_consumer_);
  const BlockChangeLog::Changes mesh = mesh_->take(*store_mesh_consumer_);
  for (const BlockChangeLog::Changes* changes : {&map, &mesh}) {
    if (map_store_) {
      checkpoint_dirty_.insert(changes->updated.begin(), changes->updated.end());
      checkpoint_dirty_.insert(changes->erased.begin(), changes->erased.end());
    }
    // (A mesh change "erased" is a submesh gone from a block that stays.)
    if (store_)
      for (const std::vector<BlockKey>* keys : {&changes->updated, &changes->erased})
        for (const BlockKey& key : *keys)
          if (const VoxelBlock* block = octree_.find(key)) pageState(*block).page_current = false;
  }
}

std::vector<BlockKey> Mapper::allBlockKeys() const {
  std::vector<BlockKey> keys = paged_.sortedKeys();
  const size_t paged = keys.size();
  for (const VoxelBlock* block : octree_.blocks()) keys.push_back(block->key);
  std::sort(keys.begin() + static_cast<std::ptrdiff_t>(paged), keys.end());
  std::inplace_merge(keys.begin(), keys.begin() + static_cast<std::ptrdiff_t>(paged), keys.end());
  return keys;
}

bool Mapper::checkpoint(const std::string& owner_note, std::string* error) {
  if (!map_store_) {
    *error = "no map store (checkpoint_period_s, resume and map_store_path make one)";
    return false;
  }
  foldCommittedCheckpoints();  // a refused one makes this one rewrite the store whole
  const Timer timer;
  const auto started = std::chrono::steady_clock::now();
  noteStoreChanges();
  StoreCommit commit;
  commit.clear_first = checkpoint_full_;
  std::vector<BlockKey> keys;
  if (checkpoint_full_) {
    keys = allBlockKeys();
  } else {
    keys.assign(checkpoint_dirty_.begin(), checkpoint_dirty_.end());
    std::sort(keys.begin(), keys.end());
  }
  size_t bytes = 0;
  std::optional<BlockStore::ReadBatch> batch;
  if (store_ && !paged_.empty()) {
    writer_->releaseWritten();
    batch.emplace(store_.get());
  }
  for (const BlockKey& key : keys) {
    auto page = std::make_shared<std::vector<uint8_t>>();
    if (const VoxelBlock* block = octree_.find(key)) {
      encodePage(*block, eviction_.lastUpdateFrame(*block), page.get());
    } else if (paged_.contains(key)) {
      std::string why;
      if (!readPage(key, page.get(), &*batch, &why)) {
        // Its page is lost (counted by paging): the store keeps its last checkpoint's.
        continue;
      }
    } else {
      commit.erase.push_back(key);
      continue;
    }
    bytes += page->size();
    commit.keys.push_back(key);
    commit.pages.push_back(std::move(page));
  }
  CheckpointState state;
  state.frames_integrated = frames_integrated_;
  MapFileInfo sections;
  for (const LayerSlot& slot : layers_) slot.layer->encode(&sections);
  state.free_space = std::move(sections.free_space);
  for (BlockChangeLog::Consumer c = 0;
       c < static_cast<BlockChangeLog::Consumer>(map_changes_.consumerCount()); ++c) {
    if (c == *store_map_consumer_) continue;
    BlockChangeLog::Changes pending = map_changes_.peek(c);
    if (pending.empty()) continue;
    state.pending.push_back(
        {map_changes_.name(c), std::move(pending.updated), std::move(pending.erased)});
  }
  state.owner_note = owner_note;
  commit.state = encodeCheckpointState(state);
  const CheckpointInFlight in_flight{
      0, frames_integrated_, commit.keys.size(), commit.erase.size(), bytes, started};
  checkpoints_in_flight_.push_back(in_flight);
  checkpoints_in_flight_.back().batch = map_store_->commit(std::move(commit));
  checkpoint_dirty_.clear();
  checkpoint_full_ = false;
  checkpoint_stats_.last_ms = timer.elapsedMs();
  checkpoint_stats_.max_ms = std::max(checkpoint_stats_.max_ms, checkpoint_stats_.last_ms);
  return true;
}

void Mapper::foldCommittedCheckpoints() {
  if (!map_store_) return;
  std::vector<BlockKey> refused;
  std::string why;
  if (map_store_->failedKeys(&refused, &why)) {
    // A full disk, a store gone: the store keeps its last committed checkpoint; the next one
    // rewrites it whole.
    map_store_->forgetFailed();
    checkpoints_in_flight_.clear();
    checkpoint_full_ = true;
    checkpoint_stats_.error = "a checkpoint was refused, the store keeps the one before: " + why;
    return;
  }
  const uint64_t written = map_store_->writtenBatches();
  bool any = false;
  while (!checkpoints_in_flight_.empty() && checkpoints_in_flight_.front().batch < written) {
    const CheckpointInFlight& done = checkpoints_in_flight_.front();
    ++checkpoint_stats_.checkpoints;
    checkpoint_stats_.last_frames_integrated = done.frames_integrated;
    checkpoint_stats_.blocks_written += done.blocks_written;
    checkpoint_stats_.blocks_erased += done.blocks_erased;
    checkpoint_stats_.bytes_written += done.bytes_written;
    checkpoint_stats_.last_commit_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - done.started).count();
    checkpoints_in_flight_.pop_front();
    checkpoint_stats_.error.clear();
    any = true;
  }
  if (any) map_store_->releaseWritten();  // nobody reads the map store's pages back
}

void Mapper::flushCheckpoints() {
  if (!map_store_) return;
  map_store_->flush();
  foldCommittedCheckpoints();
}

void Mapper::handOverMapStore(Mapper* to) {
  if (!map_store_ || to == this) return;
  flushCheckpoints();
  to->map_store_ = std::move(map_store_);
  to->checkpoint_stats_ = checkpoint_stats_;
  to->checkpoint_stats_.resumed = false;
  to->subscribeStoreConsumers();
  to->noteStoreChanges();  // the rebuild's changes: the next checkpoint writes the store whole
  to->checkpoint_full_ = true;
  to->checkpoint_dirty_.clear();
}

}  // namespace stereo_fusion
