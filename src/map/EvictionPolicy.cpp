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
                                             const EvictionLimits& limits) const {
  std::vector<BlockKey> evict;
  const bool by_distance = limits.max_distance_from_camera_m > 0.0;
  const bool by_budget = limits.max_blocks > 0 && map.blockCount() > limits.max_blocks;
  if (!by_distance && !by_budget) return evict;

  struct Candidate {
    uint64_t last_update_frame;
    double distance_m;
    BlockKey key;
  };
  std::vector<Candidate> keep;
  keep.reserve(map.blockCount());
  const Eigen::Vector3d half_block = Eigen::Vector3d::Constant(0.5 * map.blockSize());
  for (const VoxelBlock* block : map.blocks()) {
    const double distance_m = (map.blockOrigin(block->key) + half_block - camera_position_m).norm();
    if (by_distance && distance_m > limits.max_distance_from_camera_m)
      evict.push_back(block->key);
    else
      keep.push_back({lastUpdateFrame(*block), distance_m, block->key});
  }
  if (limits.max_blocks > 0 && keep.size() > limits.max_blocks) {
    const size_t excess = keep.size() - limits.max_blocks;
    auto older = [](const Candidate& a, const Candidate& b) {
      if (a.last_update_frame != b.last_update_frame)
        return a.last_update_frame < b.last_update_frame;
      if (a.distance_m != b.distance_m) return a.distance_m > b.distance_m;
      return a.key < b.key;
    };
    std::nth_element(keep.begin(), keep.begin() + (excess - 1), keep.end(), older);
    for (size_t i = 0; i < excess; ++i) evict.push_back(keep[i].key);
  }
  std::sort(evict.begin(), evict.end());
  return evict;
}

}  // namespace stereo_fusion
