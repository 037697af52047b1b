#include "stereo_fusion/planning/PlanningMap.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>

#include "stereo_fusion/planning/TsdfOccupancy.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace {
/// The max distance in cells², rounded down: the ESDF's integer bound.
uint32_t maxDist2(const PlanningConfig& config) {
  const double cells = config.max_distance_m / config.cell_m;
  return static_cast<uint32_t>(std::floor(cells * cells + 1e-9));
}
}  // namespace

PlanningMap::PlanningMap(const PlanningConfig& config, ThreadPool* pool)
    : config_(config),
      grid_{config.cell_m},
      pool_(pool),
      recorder_(FreeSpaceRecorder::Params{config.cell_m, config.unmeasured_range_m, config.band},
                pool),
      max_dist2_(maxDist2(config)),
      transit_(max_dist2_) {}

TsdfCellParams PlanningMap::cellParams() const {
  return {config_.voxels_per_cell, static_cast<float>(config_.cell_m / config_.voxels_per_cell),
          config_.min_weight};
}

PlanningBlock* PlanningMap::allocate(const BlockKey& key) {
  auto& slot = blocks_[key];
  if (!slot) {
    slot = std::make_unique<PlanningBlock>();
    fresh_.push_back(key);
    noteSizeLocked();
  }
  return slot.get();
}

void PlanningMap::noteSizeLocked() {
  block_count_.store(blocks_.size(), std::memory_order_relaxed);
  bucket_count_.store(blocks_.bucket_count(), std::memory_order_relaxed);
}

namespace {
bool inside(const CellBox& inner, const CellBox& outer) {
  return !outer.empty() && (inner.min.array() >= outer.min.array()).all() &&
         (inner.max.array() <= outer.max.array()).all();
}
/// Whether `now` grew past `acted_on`, the box the transit rule last acted on: a box that grows
/// can come within reach of new blocks, or see them along other lines.
bool grew(const CellBox& now, const CellBox& acted_on) {
  return !now.empty() && !inside(now, acted_on);
}
}  // namespace

uint64_t PlanningMap::applyTransitRule(std::vector<BlockKey> keys) {
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  transit_.beginPass();
  uint64_t allocated = 0;
  for (const BlockKey& key : keys) {
    const auto it = blocks_.find(key);
    if (it == blocks_.end()) continue;
    PlanningBlock& block = *it->second;
    const CellBox occupied = occupiedBox(key, block), free = freeBox(key, block);
    const uint8_t grown = (grew(occupied, block.rule_occupied_box) ? kHoldsOccupied : 0) |
                          (grew(free, block.rule_free_box) ? kHoldsFree : 0);
    block.rule_occupied_box = occupied;
    block.rule_free_box = free;
    block.rule_queued = false;
    if (!grown) continue;
    for (const BlockKey& transit : transit_.needed(blocks_, key, grown)) {
      allocate(transit);
      ++allocated;
    }
  }
  return allocated;
}

uint64_t PlanningMap::eraseUnknownBlocks(std::vector<BlockKey> keys) {
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<BlockKey> erased;
  for (const BlockKey& key : keys) {
    const auto it = blocks_.find(key);
    if (it != blocks_.end() && !it->second->anyKnown()) {
      blocks_.erase(it);
      erased.push_back(key);
    }
  }
  noteSizeLocked();
  // An erased block may have been one a pair of its neighbours needed: they look again.
  std::vector<BlockKey> neighbours;
  const int r = transit_.reachBlocks() + 1;
  for (const BlockKey& key : erased)
    for (int dz = -r; dz <= r; ++dz)
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          const auto it = blocks_.find(key.offset(dx, dy, dz));
          PlanningBlock* block = it == blocks_.end() ? nullptr : it->second.get();
          if (block && !(block->rule_occupied_box.empty() && block->rule_free_box.empty())) {
            block->rule_occupied_box = block->rule_free_box = CellBox{};  // acts on all again
            neighbours.push_back(it->first);
          }
        }
  applyTransitRule(std::move(neighbours));
  return erased.size();
}

FreeSpaceStats PlanningMap::recordFreeSpace(const StereoFrame& frame,
                                            const MeasurementImage& measurements) {
  const FreeSpaceStats stats = recorder_.record(frame, measurements, &seen_scratch_);
  addSeenFree(seen_scratch_);
  return stats;
}

namespace {
/// The TSDF's cell states of `keys`, computed in parallel (reads the octree only).
std::vector<std::vector<TsdfCellState>> readTsdfCells(const BlockOctree& octree,
                                                      const std::vector<BlockKey>& keys,
                                                      const TsdfCellParams& params,
                                                      ThreadPool* pool) {
  std::vector<std::vector<TsdfCellState>> states(keys.size());
  pool->parallelFor(keys.size(), 16, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      tsdfCellStates(keys[i], octree.find(keys[i]), params, &states[i]);
  });
  return states;
}
}  // namespace

PlanningUpdateStats PlanningMap::update(const BlockOctree& octree,
                                        const std::vector<BlockKey>& updated,
                                        const std::vector<BlockKey>& erased) {
  return finishUpdate(beginUpdate(octree, updated, erased));
}

PlanningMap::PendingUpdate PlanningMap::beginUpdate(const BlockOctree& octree,
                                                    const std::vector<BlockKey>& updated,
                                                    const std::vector<BlockKey>& erased) {
  {
    std::unique_lock<std::mutex> order = awaitNoUpdate();
    update_running_ = true;
  }
  PendingUpdate pending;
  pending.map_ = this;
  PlanningUpdateStats& stats = pending.stats;
  std::vector<BlockKey> keys = updated;
  keys.insert(keys.end(), erased.begin(), erased.end());
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  stats.tsdf_blocks = keys.size();
  Timer read_timer;
  pending.states = readTsdfCells(octree, keys, cellParams(), pool_);
  stats.read_ms = read_timer.elapsedMs();
  return pending;
}

PlanningUpdateStats PlanningMap::finishUpdate(
    PendingUpdate pending, const std::function<void(const PlanningUpdateStats&)>& before_end) {
  if (pending.map_ != this)
    throw std::logic_error("PlanningMap::finishUpdate: not an update this layer began");
  // `pending` ends the update if anything below throws (its destructor).
  PlanningUpdateStats stats = pending.stats;
  const auto& states = pending.states;
  std::unique_lock lock(mutex_);
  const size_t fresh_before = fresh_.size();
  std::vector<CellIndex> flipped;
  std::vector<BlockKey> maybe_empty, touched;
  flipped.swap(pending_flips_);
  maybe_empty.swap(maybe_empty_);
  for (const auto& block_states : states)
    for (const TsdfCellState& s : block_states) {
      const BlockKey key = planningBlockOf(s.cell);
      const int cell = cellInBlock(s.cell);
      PlanningBlock* block;
      if (s.observed) {
        block = allocate(key);
      } else {
        const auto it = blocks_.find(key);
        if (it == blocks_.end()) continue;
        block = it->second.get();
        if (PlanningBlock::test(block->tsdf_observed, cell)) maybe_empty.push_back(key);
      }
      if (touched.empty() || touched.back() != key) touched.push_back(key);
      PlanningBlock::set(&block->tsdf_observed, cell, s.observed);
      block->centre_sdf[cell] = PlanningBlock::quantizeCentreSdf(s.centre_sdf_m, grid_.cell_m);
      if (PlanningBlock::test(block->occupied, cell) != s.occupied) {
        PlanningBlock::set(&block->occupied, cell, s.occupied);
        flipped.push_back(s.cell);
      }
    }
  touched.insert(touched.end(), fresh_.begin(), fresh_.end());
  touched.insert(touched.end(), boxes_grown_.begin(), boxes_grown_.end());
  touched.insert(touched.end(), maybe_empty.begin(), maybe_empty.end());
  boxes_grown_.clear();
  Timer transit_timer;
  stats.transit_allocated = applyTransitRule(std::move(touched));
  stats.transit_ms = transit_timer.elapsedMs();
  stats.blocks_allocated = fresh_.size() - fresh_before;
  Timer propagate_timer;
  stats.esdf = propagator_.update(&blocks_, flipped, fresh_, max_dist2_);
  stats.propagate_ms = propagate_timer.elapsedMs();
  fresh_.clear();
  stats.blocks_erased = eraseUnknownBlocks(std::move(maybe_empty));
  lock.unlock();  // never held while taking update_mutex_ (clears take that one first)
  if (before_end) before_end(stats);  // frame writes are still kept: readers see this update
  pending.map_ = nullptr;
  endUpdate();
  return stats;
}

void PlanningMap::endUpdate() {
  // The next update may begin even if adding a write throws (bad_alloc): never left running.
  struct Ender {
    PlanningMap* map;
    ~Ender() {
      {
        std::lock_guard<std::mutex> order(map->update_mutex_);
        map->update_running_ = false;
        map->kept_writes_.clear();
      }
      map->update_done_.notify_all();
    }
  } ender{this};
  // The frame writes that came meanwhile, in order; more may come while these are added.
  std::unique_lock lock(mutex_, std::defer_lock);
  for (;;) {
    std::vector<KeptWrite> kept;
    {
      std::lock_guard<std::mutex> order(update_mutex_);
      if (kept_writes_.empty()) break;  // the Ender ends the update under this same lock
      kept.swap(kept_writes_);
    }
    lock.lock();
    for (const KeptWrite& write : kept) {
      if (const auto* seen = std::get_if<SeenFree>(&write))
        addSeenFreeLocked(*seen);
      else
        dropFartherThanLocked(std::get<DropFarther>(write).point_m,
                              std::get<DropFarther>(write).max_distance_m);
    }
    lock.unlock();
  }
}

PlanningMap::PendingUpdate::~PendingUpdate() {
  if (map_ == nullptr) return;
  // Never finished (an exception): its reading is lost, the next update may begin.
  try {
    map_->endUpdate();
  } catch (...) {
  }
}

PlanningMap::PendingUpdate& PlanningMap::PendingUpdate::operator=(PendingUpdate&& other) noexcept {
  if (this == &other) return *this;
  PendingUpdate ended(std::move(*this));  // ends an unfinished update, as the destructor does
  map_ = std::exchange(other.map_, nullptr);
  stats = other.stats;
  states = std::move(other.states);
  return *this;
}

bool PlanningMap::keepForUpdate(KeptWrite&& write) {
  std::lock_guard<std::mutex> order(update_mutex_);
  if (!update_running_) return false;
  kept_writes_.push_back(std::move(write));
  ++writes_kept_;
  return true;
}

std::unique_lock<std::mutex> PlanningMap::awaitNoUpdate() const {
  std::unique_lock<std::mutex> order(update_mutex_);
  update_done_.wait(order, [&] { return !update_running_; });
  return order;
}

uint64_t PlanningMap::writesKeptForUpdate() const {
  std::lock_guard<std::mutex> order(update_mutex_);
  return writes_kept_;
}

PlanningUpdateStats PlanningMap::rebuild(const BlockOctree& octree) {
  PlanningUpdateStats stats;
  const std::vector<VoxelBlock*> tsdf = octree.blocksSortedByKey();
  std::vector<BlockKey> keys;
  keys.reserve(tsdf.size());
  for (const VoxelBlock* b : tsdf) keys.push_back(b->key);
  stats.tsdf_blocks = keys.size();
  const auto states = readTsdfCells(octree, keys, cellParams(), pool_);
  const std::unique_lock<std::mutex> order = awaitNoUpdate();
  std::unique_lock lock(mutex_);
  for (auto& [key, block] : blocks_) {
    block->tsdf_observed.fill(0);
    block->occupied.fill(0);
    block->centre_sdf.fill(0);
  }
  for (const auto& block_states : states)
    for (const TsdfCellState& s : block_states) {
      if (!s.observed) continue;
      PlanningBlock* block = allocate(planningBlockOf(s.cell));
      const int cell = cellInBlock(s.cell);
      PlanningBlock::set(&block->tsdf_observed, cell, true);
      PlanningBlock::set(&block->occupied, cell, s.occupied);
      block->centre_sdf[cell] = PlanningBlock::quantizeCentreSdf(s.centre_sdf_m, grid_.cell_m);
    }
  std::vector<BlockKey> all;
  for (auto it = blocks_.begin(); it != blocks_.end();) {
    if (it->second->anyKnown()) {
      it->second->rule_occupied_box = it->second->rule_free_box = CellBox{};
      all.push_back(it->first);
      ++it;
    } else {
      it = blocks_.erase(it);
      ++stats.blocks_erased;
    }
  }
  noteSizeLocked();
  stats.transit_allocated = applyTransitRule(std::move(all));
  stats.blocks_allocated = fresh_.size();
  fresh_.clear();
  pending_flips_.clear();
  maybe_empty_.clear();
  boxes_grown_.clear();
  stats.esdf = propagator_.rebuild(&blocks_, max_dist2_);
  return stats;
}

void PlanningMap::clearRegion(const MapRegion& region) {
  const std::unique_lock<std::mutex> order = awaitNoUpdate();
  std::unique_lock lock(mutex_);
  const double block_m = grid_.blockM();
  for (auto& [key, block] : blocks_) {
    const Eigen::Vector3d origin(key.x * block_m, key.y * block_m, key.z * block_m);
    if (!region.intersects(
            Eigen::AlignedBox3d(origin, origin + Eigen::Vector3d::Constant(block_m))))
      continue;
    for (int cell = 0; cell < PlanningBlock::kCells; ++cell)
      if (region.contains(grid_.centre(cellOf(key, cell))))
        PlanningBlock::set(&block->seen_free, cell, false);
    maybe_empty_.push_back(key);
  }
}

void PlanningMap::dropFartherThan(const Eigen::Vector3d& point_m, double max_distance_m) {
  if (keepForUpdate(DropFarther{point_m, max_distance_m})) return;
  std::unique_lock lock(mutex_);
  dropFartherThanLocked(point_m, max_distance_m);
}

void PlanningMap::dropFartherThanLocked(const Eigen::Vector3d& point_m, double max_distance_m) {
  const double block_m = grid_.blockM();
  for (auto& [key, block] : blocks_) {
    const Eigen::Vector3d centre((key.x + 0.5) * block_m, (key.y + 0.5) * block_m,
                                 (key.z + 0.5) * block_m);
    if ((centre - point_m).norm() <= max_distance_m) continue;
    // Its occupied cells go through the ESDF as flips at the next update, which then erases it.
    for (int cell = 0; cell < PlanningBlock::kCells; ++cell)
      if (PlanningBlock::test(block->occupied, cell)) pending_flips_.push_back(cellOf(key, cell));
    block->seen_free.fill(0);
    block->tsdf_observed.fill(0);
    block->occupied.fill(0);
    block->centre_sdf.fill(0);
    maybe_empty_.push_back(key);
  }
}

void PlanningMap::clear() {
  const std::unique_lock<std::mutex> order = awaitNoUpdate();
  std::unique_lock lock(mutex_);
  blocks_.clear();
  noteSizeLocked();
  fresh_.clear();
  pending_flips_.clear();
  maybe_empty_.clear();
  boxes_grown_.clear();
}

std::vector<std::pair<BlockKey, PlanningBlock::Bits>> PlanningMap::seenFree() const {
  const std::unique_lock<std::mutex> order = awaitNoUpdate();  // with the writes kept for it
  std::shared_lock lock(mutex_);
  std::vector<std::pair<BlockKey, PlanningBlock::Bits>> out;
  for (const auto& [key, block] : blocks_)
    if (PlanningBlock::any(block->seen_free)) out.emplace_back(key, block->seen_free);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

void PlanningMap::addSeenFree(
    const std::vector<std::pair<BlockKey, PlanningBlock::Bits>>& seen_free) {
  if (keepForUpdate(SeenFree(seen_free))) return;
  std::unique_lock lock(mutex_);
  addSeenFreeLocked(seen_free);
}

void PlanningMap::addSeenFreeLocked(const SeenFree& seen_free) {
  for (const auto& [key, bits] : seen_free) {
    PlanningBlock* block = allocate(key);
    for (size_t w = 0; w < bits.size(); ++w) block->seen_free[w] |= bits[w];
    if (!block->rule_queued && grew(freeBox(key, *block), block->rule_free_box)) {
      block->rule_queued = true;
      boxes_grown_.push_back(key);
    }
  }
}

size_t PlanningMap::blockCount() const { return block_count_.load(std::memory_order_relaxed); }

namespace {
// Per block: key, pointer and hash-node overhead of the table entry.
constexpr size_t kEntryBytes = sizeof(BlockKey) + sizeof(void*) * 3;
constexpr size_t kBitsBytes = 3 * sizeof(PlanningBlock::Bits);
}  // namespace

size_t PlanningMap::freeSpaceBytes() const {
  return blockCount() * (kEntryBytes + kBitsBytes) +
         bucket_count_.load(std::memory_order_relaxed) * sizeof(void*);
}

size_t PlanningMap::esdfBytes() const {
  return blockCount() * (sizeof(PlanningBlock) - kBitsBytes);
}

}  // namespace stereo_fusion
