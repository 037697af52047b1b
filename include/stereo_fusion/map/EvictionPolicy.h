#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "stereo_fusion/map/BlockOctree.h"

namespace stereo_fusion {

/// The memory bound of the map (parameters max_blocks and max_distance_from_camera_m).
struct EvictionLimits {
  size_t max_blocks = 0;                  ///< 0 = unlimited
  double max_distance_from_camera_m = 0;  ///< 0 = unlimited
};

/// Blocks to evict after a frame seen from `camera_position_m`, sorted by key: first every
/// block whose centre is farther than the distance limit, then, while more than max_blocks
/// remain, the least recently updated (smallest last_update_frame; never-updated blocks
/// first), the farther first among equals, then by key, so the choice is deterministic.
std::vector<BlockKey> selectBlocksToEvict(const BlockOctree& map, const Eigen::Vector3d& camera_position_m,
                                          const EvictionLimits& limits);

}  // namespace stereo_fusion
