#include "stereo_fusion/integration/BlockLookup.h"

#include <algorithm>
#include <atomic>
#include <cmath>

namespace stereo_fusion {

BlockLookup::BlockLookup(const MapperConfig& config, ThreadPool* pool)
    : config_(config), pool_(pool) {}

BlockLookup::PixelGeometry BlockLookup::pixelGeometry(const StereoFrame& frame,
                                                      const BlockOctree& octree) const {
  PixelGeometry g;
  g.R_world_camera = frame.T_world_camera.linear();
  g.t_world_camera = frame.T_world_camera.translation();
  const StereoCamera& cam = frame.camera;
  g.fb = cam.fx() * cam.baseline();
  g.cx = cam.cx();
  g.cy = cam.cy();
  g.inv_fx = 1.0 / cam.fx();
  g.inv_fy = 1.0 / cam.fy();
  g.inv_block_size = 1.0 / octree.blockSize();
  g.min_depth_m = config_.min_depth_m;
  g.max_depth_m = config_.max_depth_m;
  g.levels = config_.levels;
  for (int level = 0; level < kNumLevels; ++level)
    g.band_blocks[level] = config_.truncation_vox * levelScale(level) * config_.voxel_size_m * g.inv_block_size;
  return g;
}

// Inline: called for every pixel (a call per pixel cost a fifth of the lookup).
inline bool BlockLookup::bandBoxOfPixel(float d, int u, int v, BandBox* box) const {
  const PixelGeometry& g = geometry_;
  if (!(d > 0.0f) || !std::isfinite(d)) return false;
  const double z = g.fb / d;
  if (!(z >= g.min_depth_m && z <= g.max_depth_m)) return false;
  const Eigen::Vector3d p_camera((u - g.cx) * z * g.inv_fx, (v - g.cy) * z * g.inv_fy, z);
  const Eigen::Vector3d p_blocks = (g.R_world_camera * p_camera + g.t_world_camera) * g.inv_block_size;
  const double band = g.band_blocks[levelForDepth(z, g.levels)];
  box->lo = BlockOctree::keyForBlockCoordinates(p_blocks.array() - band);
  box->hi = BlockOctree::keyForBlockCoordinates(p_blocks.array() + band);
  return BlockOctree::keyInRange(box->lo) && BlockOctree::keyInRange(box->hi);
}

template <typename F>
static void forEachKeyInBox(const BlockKey& lo, const BlockKey& hi, F&& f) {
  for (int32_t z = lo.z; z <= hi.z; ++z)
    for (int32_t y = lo.y; y <= hi.y; ++y)
      for (int32_t x = lo.x; x <= hi.x; ++x) f(BlockKey{x, y, z});
}

void BlockLookup::gatherHistogram(const StereoFrame& frame, const cv::Rect& region, RegionScratch* s) const {
  // Neighbouring pixels almost always share a band box, so count points per distinct box
  // first (a comparison with the previous box per pixel) and expand boxes to blocks after.
  s->boxes.clear();
  s->key_counts.clear();
  size_t last = 0;
  for (int v = region.y; v < region.y + region.height; ++v) {
    const float* disparity_row = frame.disparity_px.ptr<float>(v);
    for (int u = region.x; u < region.x + region.width; ++u) {
      BandBox box;
      if (!bandBoxOfPixel(disparity_row[u], u, v, &box)) continue;
      ++s->stats.valid_points;
      if (last < s->boxes.size() && s->boxes[last].first == box) {
        ++s->boxes[last].second;
        continue;
      }
      auto it = std::find_if(s->boxes.begin(), s->boxes.end(),
                             [&](const auto& entry) { return entry.first == box; });
      if (it == s->boxes.end()) {
        s->boxes.emplace_back(box, 1);
        last = s->boxes.size() - 1;
      } else {
        ++it->second;
        last = static_cast<size_t>(it - s->boxes.begin());
      }
    }
  }
  if (s->boxes.empty()) return;
  // Expand boxes to per-block counts. Boxes overlap heavily (coarse levels reach 2 blocks
  // either side), so count on a dense grid over their union when it is small, which it is
  // unless the region straddles a large depth jump; otherwise merge keys linearly.
  BlockKey lo = s->boxes.front().first.lo, hi = s->boxes.front().first.hi;
  for (const auto& box_count : s->boxes) {
    const BandBox& box = box_count.first;
    lo = {std::min(lo.x, box.lo.x), std::min(lo.y, box.lo.y), std::min(lo.z, box.lo.z)};
    hi = {std::max(hi.x, box.hi.x), std::max(hi.y, box.hi.y), std::max(hi.z, box.hi.z)};
  }
  const int64_t nx = int64_t{hi.x} - lo.x + 1, ny = int64_t{hi.y} - lo.y + 1, nz = int64_t{hi.z} - lo.z + 1;
  if (nx * ny * nz <= kMaxDenseHistogramCells) {
    s->dense_counts.assign(static_cast<size_t>(nx * ny * nz), 0);
    for (const auto& box_count : s->boxes) {
      const BandBox& box = box_count.first;
      for (int32_t z = box.lo.z; z <= box.hi.z; ++z)
        for (int32_t y = box.lo.y; y <= box.hi.y; ++y) {
          int* row = &s->dense_counts[static_cast<size_t>(((z - lo.z) * ny + (y - lo.y)) * nx - lo.x)];
          for (int32_t x = box.lo.x; x <= box.hi.x; ++x) row[x] += box_count.second;
        }
    }
    size_t i = 0;
    for (int32_t z = lo.z; z <= hi.z; ++z)
      for (int32_t y = lo.y; y <= hi.y; ++y)
        for (int32_t x = lo.x; x <= hi.x; ++x, ++i)
          if (s->dense_counts[i] > 0) s->key_counts.emplace_back(BlockKey{x, y, z}, s->dense_counts[i]);
    return;
  }
  // Not a structured binding: lambdas may capture those only from C++20 (clang refuses).
  for (const auto& box_count : s->boxes) {
    const auto& box = box_count.first;
    const auto count = box_count.second;
    forEachKeyInBox(box.lo, box.hi, [&](const BlockKey& key) {
      auto it = std::find_if(s->key_counts.begin(), s->key_counts.end(),
                             [&](const auto& entry) { return entry.first == key; });
      if (it == s->key_counts.end())
        s->key_counts.emplace_back(key, count);
      else
        it->second += count;
    });
  }
}

bool BlockLookup::passesFilter(const RegionScratch& s, const BlockKey& key) const {
  if (config_.histogram_min_points <= 0) return true;
  for (const auto& [k, count] : s.key_counts)
    if (k == key) return count >= config_.histogram_min_points;
  return false;
}

void BlockLookup::runRegionAccelerated(const StereoFrame& frame, const cv::Rect& region,
                                       RegionScratch* s) const {
  gatherHistogram(frame, region, s);
  s->passing.clear();
  for (const auto& [key, count] : s->key_counts) {
    if (config_.histogram_min_points > 0 && count < config_.histogram_min_points) {
      ++s->stats.blocks_filtered;
      continue;
    }
    s->passing.push_back(key);
  }
}

void BlockLookup::collectDistinctKeys(size_t num_regions) {
  // Neighbouring regions share most of their blocks (≈10 regions per block at 1 cm): one
  // octree search per distinct block of the frame instead of one per (region, block).
  // Open addressing with a per-slot generation, so the table is never cleared.
  size_t total = 0;
  for (size_t r = 0; r < num_regions; ++r) total += scratch_[r].passing.size();
  size_t capacity = 64;
  while (capacity < 2 * total) capacity *= 2;
  if (key_table_.size() < capacity) {
    key_table_.assign(capacity, KeySlot{});
    key_table_generation_ = 0;
  }
  const size_t mask = key_table_.size() - 1;
  if (++key_table_generation_ == 0) {  // wrapped: stale slots could look current
    std::fill(key_table_.begin(), key_table_.end(), KeySlot{});
    key_table_generation_ = 1;
  }
  const uint32_t generation = key_table_generation_;
  frame_keys_.clear();
  for (size_t r = 0; r < num_regions; ++r)
    for (const BlockKey& key : scratch_[r].passing) {
      for (size_t i = BlockKeyHash{}(key) & mask;; i = (i + 1) & mask) {
        KeySlot& slot = key_table_[i];
        if (slot.generation != generation) {
          slot = {key, generation};
          frame_keys_.push_back(key);
          break;
        }
        if (slot.key == key) break;
      }
    }
}

void BlockLookup::runRegionNaive(const StereoFrame& frame, const cv::Rect& region,
                                 BlockOctree* octree, RegionScratch* s) const {
  const bool filter = config_.histogram_min_points > 0;
  if (filter) {
    gatherHistogram(frame, region, s);
    for (const auto& [key, count] : s->key_counts)
      s->stats.blocks_filtered += count < config_.histogram_min_points;
    s->stats.valid_points = 0;  // counted again below
  }
  for (int v = region.y; v < region.y + region.height; ++v) {
    const float* disparity_row = frame.disparity_px.ptr<float>(v);
    for (int u = region.x; u < region.x + region.width; ++u) {
      BandBox box;
      if (!bandBoxOfPixel(disparity_row[u], u, v, &box)) continue;
      ++s->stats.valid_points;
      forEachKeyInBox(box.lo, box.hi, [&](const BlockKey& key) {
        if (filter && !passesFilter(*s, key)) return;
        bool allocated = false;
        ++s->stats.octree_searches;
        VoxelBlock* block = octree->findOrAllocate(key, &allocated);
        s->stats.blocks_allocated += allocated;
        if (block != nullptr && (s->found.empty() || s->found.back() != block))
          s->found.push_back(block);
      });
    }
  }
}

LookupStats BlockLookup::run(const StereoFrame& frame, BlockOctree* octree,
                             std::vector<VoxelBlock*>* queue) {
  const int region_px = config_.lookup_region_px;
  const int cols = (frame.disparity_px.cols + region_px - 1) / region_px;
  const int rows = (frame.disparity_px.rows + region_px - 1) / region_px;
  const size_t num_regions = static_cast<size_t>(cols) * rows;
  if (scratch_.size() < num_regions) scratch_.resize(num_regions);
  geometry_ = pixelGeometry(frame, *octree);

  const bool accelerated = config_.lookup_mode == LookupMode::kAccelerated;
  pool_->parallelFor(num_regions, 4, [&](size_t begin, size_t end) {
    for (size_t r = begin; r < end; ++r) {
      RegionScratch& s = scratch_[r];
      s.found.clear();
      s.stats = LookupStats{};
      const int x = static_cast<int>(r % cols) * region_px;
      const int y = static_cast<int>(r / cols) * region_px;
      const cv::Rect region(x, y, std::min(region_px, frame.disparity_px.cols - x),
                            std::min(region_px, frame.disparity_px.rows - y));
      if (accelerated)
        runRegionAccelerated(frame, region, &s);
      else
        runRegionNaive(frame, region, octree, &s);
    }
  });

  LookupStats total;
  for (size_t r = 0; r < num_regions; ++r) {
    const LookupStats& stats = scratch_[r].stats;
    total.valid_points += stats.valid_points;
    total.octree_searches += stats.octree_searches;
    total.blocks_allocated += stats.blocks_allocated;
    total.blocks_filtered += stats.blocks_filtered;
  }
  queue->clear();
  if (accelerated) {
    collectDistinctKeys(num_regions);
    frame_blocks_.resize(frame_keys_.size());
    frame_allocated_.resize(frame_keys_.size());
    pool_->parallelFor(frame_keys_.size(), 64, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) {
        bool allocated = false;
        frame_blocks_[i] = octree->findOrAllocate(frame_keys_[i], &allocated);
        frame_allocated_[i] = allocated;
      }
    });
    total.octree_searches += frame_keys_.size();
    for (size_t i = 0; i < frame_keys_.size(); ++i) {
      total.blocks_allocated += frame_allocated_[i];
      if (frame_blocks_[i] != nullptr) queue->push_back(frame_blocks_[i]);
    }
  } else {
    // Regions overlap in blocks: keep each block's first find. Stamps are unique across all
    // BlockLookup instances, so two lookups on one octree never mistake each other's marks.
    static std::atomic<uint64_t> last_stamp{0};
    const uint64_t stamp = ++last_stamp;
    for (size_t r = 0; r < num_regions; ++r)
      for (VoxelBlock* block : scratch_[r].found) {
        if (block->lookup_stamp == stamp) continue;
        block->lookup_stamp = stamp;
        queue->push_back(block);
      }
  }
  std::sort(queue->begin(), queue->end(),
            [](const VoxelBlock* a, const VoxelBlock* b) { return a->key < b->key; });
  total.blocks_queued = queue->size();
  return total;
}

}  // namespace stereo_fusion
