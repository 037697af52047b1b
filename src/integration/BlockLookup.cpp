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
  for (int level = 0; level < kNumLevels; ++level)
    g.band_blocks[level] = config_.truncation_vox * levelScale(level) * config_.voxel_size_m * g.inv_block_size;
  return g;
}

bool BlockLookup::bandBoxOfPixel(const StereoFrame& frame, int u, int v, BandBox* box) const {
  const PixelGeometry& g = geometry_;
  const float d = frame.disparity_px.at<float>(v, u);
  if (!(d > 0.0f) || !std::isfinite(d)) return false;
  const double z = g.fb / d;
  if (!(z >= config_.min_depth_m && z <= config_.max_depth_m)) return false;
  const Eigen::Vector3d p_camera((u - g.cx) * z * g.inv_fx, (v - g.cy) * z * g.inv_fy, z);
  const Eigen::Vector3d p_blocks = (g.R_world_camera * p_camera + g.t_world_camera) * g.inv_block_size;
  const double band = g.band_blocks[levelForDepth(z, config_.levels)];
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
    for (int u = region.x; u < region.x + region.width; ++u) {
      BandBox box;
      if (!bandBoxOfPixel(frame, u, v, &box)) continue;
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
                                       BlockOctree* octree, RegionScratch* s) const {
  gatherHistogram(frame, region, s);
  for (const auto& [key, count] : s->key_counts) {
    if (config_.histogram_min_points > 0 && count < config_.histogram_min_points) {
      ++s->stats.blocks_filtered;
      continue;
    }
    bool allocated = false;
    ++s->stats.octree_searches;
    if (VoxelBlock* block = octree->findOrAllocate(key, &allocated)) {
      s->found.push_back(block);
      s->stats.blocks_allocated += allocated;
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
    for (int u = region.x; u < region.x + region.width; ++u) {
      BandBox box;
      if (!bandBoxOfPixel(frame, u, v, &box)) continue;
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

  pool_->parallelFor(num_regions, 4, [&](size_t begin, size_t end) {
    for (size_t r = begin; r < end; ++r) {
      RegionScratch& s = scratch_[r];
      s.found.clear();
      s.stats = LookupStats{};
      const int x = static_cast<int>(r % cols) * region_px;
      const int y = static_cast<int>(r / cols) * region_px;
      const cv::Rect region(x, y, std::min(region_px, frame.disparity_px.cols - x),
                            std::min(region_px, frame.disparity_px.rows - y));
      if (config_.lookup_mode == LookupMode::kAccelerated)
        runRegionAccelerated(frame, region, octree, &s);
      else
        runRegionNaive(frame, region, octree, &s);
    }
  });

  // Regions overlap in blocks: keep each block's first find. Stamps are unique across all
  // BlockLookup instances, so two lookups on one octree never mistake each other's marks.
  static std::atomic<uint64_t> last_stamp{0};
  const uint64_t stamp = ++last_stamp;
  LookupStats total;
  queue->clear();
  for (size_t r = 0; r < num_regions; ++r) {
    const RegionScratch& s = scratch_[r];
    for (VoxelBlock* block : s.found) {
      if (block->lookup_stamp == stamp) continue;
      block->lookup_stamp = stamp;
      queue->push_back(block);
    }
    total.valid_points += s.stats.valid_points;
    total.octree_searches += s.stats.octree_searches;
    total.blocks_allocated += s.stats.blocks_allocated;
    total.blocks_filtered += s.stats.blocks_filtered;
  }
  std::sort(queue->begin(), queue->end(),
            [](const VoxelBlock* a, const VoxelBlock* b) { return a->key < b->key; });
  total.blocks_queued = queue->size();
  return total;
}

}  // namespace stereo_fusion
