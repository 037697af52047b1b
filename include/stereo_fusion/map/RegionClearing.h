#pragma once
#include <cstdint>
#include <vector>

#include "stereo_fusion/map/BlockKey.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/map/MapRegion.h"

namespace stereo_fusion {

/// What clearRegionVoxels() did.
struct RegionClearing {
  /// Blocks that lost observed voxels and keep some, sorted by key.
  std::vector<BlockKey> changed;
  /// Blocks left without any observed voxel, sorted by key: the caller erases them.
  std::vector<BlockKey> emptied;
  uint64_t blocks_visited = 0;  ///< blocks of the map the region reaches
  uint64_t voxels_cleared = 0;  ///< observed voxels made unobserved, all levels
  size_t bytes_freed = 0;  ///< voxel storage of the levels freed (emptied blocks' levels included)
};

/// Forgets the region: every observed voxel, at every level, whose centre lies in `region` is
/// made unobserved (weight 0, as never measured), and a level left without an observed voxel
/// is freed. Unobserved voxels inside are untouched, so clearing twice changes nothing the
/// second time. Blocks are only visited, never allocated or erased: the caller erases the
/// emptied ones so that its change tracking sees them go.
RegionClearing clearRegionVoxels(const MapRegion& region, BlockOctree* map);

}  // namespace stereo_fusion
