#include "stereo_fusion/map/EvictionPolicy.h"

#include <algorithm>

namespace stereo_fusion {

void EvictionPolicy::recordUpdates(const BlockOctree& map, const std::vector<BlockKey>& updated,
                                   uint64_t frame_index) {
  found_.resize(updated.size());
  map.findBatch(updated.data(), updated.size(), found_.data());
  last_update_frame_.fit(map);
  for (const VoxelBlock* block : found_)
    if (block != nullptr) last_update_frame_[*block] = frame_index;
}

void EvictionPolicy::setLastUpdateFrame(const BlockOctree& map, const VoxelBlock& block,
                                        uint64_t frame_index) {
  last_update_frame_.fit(map);
  last_update_frame_[block] = frame_index;
}

std::vector<BlockKey> EvictionPolicy::select(const BlockOctree& map,
                                             const Eigen::Vector3d& camera_position_m,
                                             const EvictionLimits& limits,
                                             const PagedBlocks* paged) const {
  std::vector<BlockKey> evict;
  const size_t paged_count = paged ? paged->size() : 0;
  const size_t total = map.blockCount() + paged_count;
  const bool by_distance = limits.max_distance_from_camera_m > 0.0;
  const bool by_budget = limits.max_blocks > 0 && total > limits.max_blocks;
  if (!by_distance && !by_budget) return evict;

  std::vector<LeaveCandidate> keep;
  keep.reserve(total);
  const Eigen::Vector3d half_block = Eigen::Vector3d::Constant(0.5 * map.blockSize());
  auto consider = [&](const BlockKey& key, uint64_t last_update_frame) {
    const double distance_m = (map.blockOrigin(key) + half_block - camera_position_m).norm();
    if (by_distance && distance_m > limits.max_distance_from_camera_m)
      evict.push_back(key);
    else
      keep.push_back({last_update_frame, distance_m, key});
  };
  for (const VoxelBlock* block : map.blocks()) consider(block->key, lastUpdateFrame(*block));
  if (paged)
    for (const auto& [key, entry] : paged->entries()) consider(key, entry.last_update_frame);
  if (limits.max_blocks > 0 && keep.size() > limits.max_blocks) {
    const size_t excess = keep.size() - limits.max_blocks;
    std::nth_element(keep.begin(), keep.begin() + (excess - 1), keep.end(), leavesFirst);
    for (size_t i = 0; i < excess; ++i) evict.push_back(keep[i].key);
  }
  std::sort(evict.begin(), evict.end());
  return evict;
}

}  // namespace stereo_fusion
