#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "stereo_fusion/map/BlockColumn.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/paging/PagedBlocks.h"

namespace stereo_fusion {

/// The memory bound of the map (parameters max_blocks and max_distance_from_camera_m).
struct EvictionLimits {
  size_t max_blocks = 0;                  ///< 0 = unlimited
  double max_distance_from_camera_m = 0;  ///< 0 = unlimited
};

/// A block as the memory bound ranks it.
struct LeaveCandidate {
  uint64_t last_update_frame;
  double distance_m;  ///< of its centre from the camera
  BlockKey key;
};
/// The order blocks leave memory in, evicted (EvictionPolicy) or paged out (the Mapper's
/// paging): the least recently updated first (never-updated blocks first), the farther first
/// among equals, then by key, so the choice is deterministic.
inline bool leavesFirst(const LeaveCandidate& a, const LeaveCandidate& b) {
  if (a.last_update_frame != b.last_update_frame) return a.last_update_frame < b.last_update_frame;
  if (a.distance_m != b.distance_m) return a.distance_m > b.distance_m;
  return a.key < b.key;
}

/// The eviction stage: it keeps, in a column of its own, the frame that last updated each block
/// (fed from the map's change log after every frame) and picks the blocks to evict.
class EvictionPolicy {
 public:
  /// Blocks `updated` (keys; those not in `map` are skipped) were changed by frame `frame_index`.
  void recordUpdates(const BlockOctree& map, const std::vector<BlockKey>& updated,
                     uint64_t frame_index);
  /// Sets one block's last update frame (a loaded map's, from its file).
  void setLastUpdateFrame(const BlockOctree& map, const VoxelBlock& block, uint64_t frame_index);
  /// The frame that last updated `block` (0: never, as far as this policy saw).
  uint64_t lastUpdateFrame(const VoxelBlock& block) const {
    return block.row < last_update_frame_.size() ? last_update_frame_[block] : 0;
  }
  /// Blocks to evict after a frame seen from `camera_position_m`, sorted by key: first every
  /// block whose centre is farther than the distance limit, then, while more than max_blocks
  /// remain, in leavesFirst() order. `paged` (may be null): the blocks paged out of `map`,
  /// which count and may be chosen like the others.
  std::vector<BlockKey> select(const BlockOctree& map, const Eigen::Vector3d& camera_position_m,
                               const EvictionLimits& limits,
                               const PagedBlocks* paged = nullptr) const;
  void clear() { last_update_frame_.clear(); }

 private:
  BlockColumn<uint64_t> last_update_frame_;
  std::vector<VoxelBlock*> found_;  // recordUpdates()' searches, reused
};

}  // namespace stereo_fusion
