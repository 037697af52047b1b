#include "stereo_fusion/integration/BlockLookup.h"

#include <algorithm>
#include <cmath>

namespace stereo_fusion {

BlockLookup::BlockLookup(const MapperConfig& config, ThreadPool* pool)
    : config_(config), pool_(pool) {}

bool BlockLookup::bandBoxOfPixel(const StereoFrame& frame, int u, int v, const BlockOctree& octree,
                                 BandBox* box) const {
  const float d = frame.disparity_px.at<float>(v, u);
  if (!(d > 0.0f) || !std::isfinite(d)) return false;
  const double z = frame.camera.depthFromDisparity(d);
  if (!(z >= config_.min_depth_m && z <= config_.max_depth_m)) return false;
  const Eigen::Vector3d p_world = frame.T_world_camera * frame.camera.backProject(u, v, z);
  const int level = levelForDepth(z, config_.levels);
  const double truncation_m = config_.truncation_vox * levelScale(level) * config_.voxel_size_m;
  const Eigen::Vector3d band(truncation_m, truncation_m, truncation_m);
  box->lo = octree.keyForPoint(p_world - band);
  box->hi = octree.keyForPoint(p_world + band);
  return BlockOctree::keyInRange(box->lo) && BlockOctree::keyInRange(box->hi);
}

template <typename F>
static void forEachKeyInBox(const BlockKey& lo, const BlockKey& hi, F&& f) {
  for (int32_t z = lo.z; z <= hi.z; ++z)
    for (int32_t y = lo.y; y <= hi.y; ++y)
      for (int32_t x = lo.x; x <= hi.x; ++x) f(BlockKey{x, y, z});
}

void BlockLookup::gatherHistogram(const StereoFrame& frame, const cv::Rect& region,
                                  const BlockOctree& octree, RegionScratch* s) const {
  // Neighbouring pixels almost always share a band box, so count points per distinct box
  // first (a comparison with the previous box per pixel) and expand boxes to blocks after.
  s->boxes.clear();
  s->key_counts.clear();
  size_t last = 0;
  for (int v = region.y; v < region.y + region.height; ++v) {
    for (int u = region.x; u < region.x + region.width; ++u) {
      BandBox box;
      if (!bandBoxOfPixel(frame, u, v, octree, &box)) continue;
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
  gatherHistogram(frame, region, *octree, s);
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
    gatherHistogram(frame, region, *octree, s);
    for (const auto& [key, count] : s->key_counts)
      s->stats.blocks_filtered += count < config_.histogram_min_points;
    s->stats.valid_points = 0;  // counted again below
  }
  for (int v = region.y; v < region.y + region.height; ++v) {
    for (int u = region.x; u < region.x + region.width; ++u) {
      BandBox box;
      if (!bandBoxOfPixel(frame, u, v, *octree, &box)) continue;
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

  LookupStats total;
  queue->clear();
  for (size_t r = 0; r < num_regions; ++r) {
    const RegionScratch& s = scratch_[r];
    queue->insert(queue->end(), s.found.begin(), s.found.end());
    total.valid_points += s.stats.valid_points;
    total.octree_searches += s.stats.octree_searches;
    total.blocks_allocated += s.stats.blocks_allocated;
    total.blocks_filtered += s.stats.blocks_filtered;
  }
  std::sort(queue->begin(), queue->end(),
            [](const VoxelBlock* a, const VoxelBlock* b) { return a->key < b->key; });
  queue->erase(std::unique(queue->begin(), queue->end()), queue->end());
  total.blocks_queued = queue->size();
  return total;
}

}  // namespace stereo_fusion
