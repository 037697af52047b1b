// BlockLookup::run(): the frame's regions in parallel, their keys gathered and split into the
// queue and the missing keys; the per-pixel band boxes are BlockLookup.cpp's.
#include "stereo_fusion/integration/BlockLookup.h"

#include <algorithm>
#include <atomic>
#include <cmath>

namespace stereo_fusion {

void BlockLookup::collectSortedDistinctKeys(size_t num_regions) {
  // Neighbouring regions share most of their blocks (≈10 regions per block at 1 cm): one
  // octree search per distinct block of the frame instead of one per (region, block).
  frame_keys_.clear();
  bool any = false;
  BlockKey lo, hi;
  for (size_t r = 0; r < num_regions; ++r) {
    const RegionScratch& s = scratch_[r];
    if (s.passing.empty()) continue;  // else it has boxes, and they hold its keys
    lo = any ? componentMin(lo, s.boxes_lo) : s.boxes_lo;
    hi = any ? componentMax(hi, s.boxes_hi) : s.boxes_hi;
    any = true;
  }
  if (!any) return;
  // The frame's blocks lie in the camera frustum, a small box: a bit per block of it
  // de-duplicates with no hashing and reads back sorted with no sort.
  if (frame_key_bitmap_.reset(lo, hi)) {
    for (size_t r = 0; r < num_regions; ++r)
      for (const BlockKey& key : scratch_[r].passing) frame_key_bitmap_.insert(key);
    frame_key_bitmap_.appendSorted(&frame_keys_);
    return;
  }
  size_t total = 0;
  for (size_t r = 0; r < num_regions; ++r) total += scratch_[r].passing.size();
  frame_key_set_.reset(total);
  for (size_t r = 0; r < num_regions; ++r)
    for (const BlockKey& key : scratch_[r].passing)
      if (frame_key_set_.insert(key)) frame_keys_.push_back(key);
  std::sort(frame_keys_.begin(), frame_keys_.end());
}

LookupStats BlockLookup::run(const StereoFrame& frame, const MeasurementImage& measurements,
                             BlockOctree* octree, std::vector<VoxelBlock*>* queue,
                             std::vector<BlockKey>* missing) {
  const bool allocate = missing == nullptr;
  if (missing) missing->clear();
  const int region_px = config_.lookup_region_px;
  const int cols = (frame.disparity_px.cols + region_px - 1) / region_px;
  const int rows = (frame.disparity_px.rows + region_px - 1) / region_px;
  const size_t num_regions = static_cast<size_t>(cols) * rows;
  if (scratch_.size() < num_regions) scratch_.resize(num_regions);
  setPixelGeometry(frame, measurements, *octree);

  const bool accelerated = config_.lookup_mode == LookupMode::kAccelerated;
  auto region_of = [&](size_t r) {
    const int x = static_cast<int>(r % cols) * region_px;
    const int y = static_cast<int>(r / cols) * region_px;
    return cv::Rect(x, y, std::min(region_px, frame.disparity_px.cols - x),
                    std::min(region_px, frame.disparity_px.rows - y));
  };
  // Pass 1: each region's distinct band boxes and the blocks they span, before any block is
  // visited, so that a frame over the work bound costs one pass over its pixels.
  pool_->parallelFor(num_regions, 4, [&](size_t begin, size_t end) {
    for (size_t r = begin; r < end; ++r) {
      RegionScratch& s = scratch_[r];
      s.found.clear();
      s.not_found.clear();
      s.passing.clear();
      s.stats = LookupStats{};
      countRegionBoxes(measurements, region_of(r), &s);
      s.stats.box_blocks = boxBlocks(s, /*per_point=*/!accelerated);
    }
  });
  uint64_t box_blocks = 0;
  for (size_t r = 0; r < num_regions; ++r)
    box_blocks = std::min(UINT64_MAX - scratch_[r].stats.box_blocks, box_blocks) +
                 scratch_[r].stats.box_blocks;
  const uint64_t bound = static_cast<uint64_t>(std::max(0, config_.max_lookup_blocks_per_frame));
  if (bound > 0 && box_blocks > bound) {
    queue->clear();
    LookupStats over;
    for (size_t r = 0; r < num_regions; ++r) over.valid_points += scratch_[r].stats.valid_points;
    over.box_blocks = box_blocks;
    over.over_work_bound = true;
    return over;
  }
  // Pass 2: expand the boxes to blocks.
  pool_->parallelFor(num_regions, 4, [&](size_t begin, size_t end) {
    for (size_t r = begin; r < end; ++r) {
      if (accelerated)
        runRegionAccelerated(region_of(r), &scratch_[r]);
      else
        runRegionNaive(measurements, region_of(r), octree, allocate, &scratch_[r]);
    }
  });

  LookupStats total;
  total.box_blocks = box_blocks;
  for (size_t r = 0; r < num_regions; ++r) {
    const LookupStats& stats = scratch_[r].stats;
    total.valid_points += stats.valid_points;
    total.octree_searches += stats.octree_searches;
    total.blocks_allocated += stats.blocks_allocated;
    total.blocks_filtered += stats.blocks_filtered;
  }
  queue->clear();
  if (accelerated) {
    // The queue goes out in key order: order the keys here, contiguous, rather than the blocks
    // afterwards through a pointer per comparison.
    collectSortedDistinctKeys(num_regions);
    frame_blocks_.resize(frame_keys_.size());
    frame_allocated_.resize(frame_keys_.size());
    // Sorted keys in batches: neighbouring keys share most of their octree path.
    pool_->parallelFor(frame_keys_.size(), 64, [&](size_t begin, size_t end) {
      if (allocate)
        octree->findOrAllocateBatch(&frame_keys_[begin], end - begin, &frame_blocks_[begin],
                                    &frame_allocated_[begin]);
      else
        octree->findBatch(&frame_keys_[begin], end - begin, &frame_blocks_[begin]);
    });
    total.octree_searches += frame_keys_.size();
    for (size_t i = 0; i < frame_keys_.size(); ++i) {
      if (allocate) total.blocks_allocated += frame_allocated_[i];
      if (frame_blocks_[i] != nullptr)
        queue->push_back(frame_blocks_[i]);
      else if (!allocate && BlockOctree::keyInRange(frame_keys_[i]))
        missing->push_back(frame_keys_[i]);  // in key order, as frame_keys_
    }
  } else {
    // Regions overlap in blocks: each block once, in key order.
    for (size_t r = 0; r < num_regions; ++r)
      queue->insert(queue->end(), scratch_[r].found.begin(), scratch_[r].found.end());
    std::sort(queue->begin(), queue->end(),
              [](const VoxelBlock* a, const VoxelBlock* b) { return a->key < b->key; });
    queue->erase(std::unique(queue->begin(), queue->end()), queue->end());
    if (missing) {
      for (size_t r = 0; r < num_regions; ++r)
        missing->insert(missing->end(), scratch_[r].not_found.begin(), scratch_[r].not_found.end());
      std::sort(missing->begin(), missing->end());
      missing->erase(std::unique(missing->begin(), missing->end()), missing->end());
    }
  }
  total.blocks_missing = missing ? missing->size() : 0;
  total.blocks_queued = queue->size() + total.blocks_missing;
  return total;
}

}  // namespace stereo_fusion
