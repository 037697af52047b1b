#include "stereo_fusion/map/RegionClearing.h"

#include <algorithm>

namespace stereo_fusion {

namespace {
/// Clears the voxels of one allocated level whose centres lie in the region; true if the level
/// still holds an observed voxel afterwards.
bool clearLevel(const MapRegion& region, const Eigen::Vector3d& origin_m, double voxel_m, int side,
                Voxel* voxels, uint64_t* cleared) {
  bool observed_left = false;
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) {
        Voxel& v = voxels[VoxelBlock::indexInLevel(side, i, j, k)];
        if (v.weight <= 0.0f) continue;
        if (region.contains(origin_m + Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5) * voxel_m)) {
          v = Voxel();
          ++*cleared;
        } else {
          observed_left = true;
        }
      }
  return observed_left;
}
}  // namespace

RegionClearing clearRegionVoxels(const MapRegion& region, BlockOctree* map) {
  RegionClearing result;
  std::vector<VoxelBlock*> blocks;
  map->collectBlocks(
      [&region](const Eigen::AlignedBox3d& box_m) { return region.intersects(box_m); }, &blocks);
  std::sort(blocks.begin(), blocks.end(),
            [](const VoxelBlock* a, const VoxelBlock* b) { return a->key < b->key; });
  result.blocks_visited = blocks.size();
  for (VoxelBlock* block : blocks) {
    const Eigen::Vector3d origin_m = map->blockOrigin(block->key);
    const uint64_t cleared_before = result.voxels_cleared;
    bool observed_left = false;
    for (int level = 0; level < kNumLevels; ++level) {
      Voxel* voxels = block->levelIfAllocated(level);
      if (voxels == nullptr) continue;
      const int side = levelSide(level);
      if (clearLevel(region, origin_m, map->blockSize() / side, side, voxels,
                     &result.voxels_cleared)) {
        observed_left = true;
      } else {
        result.bytes_freed += sizeof(Voxel) * static_cast<size_t>(levelVoxelCount(level));
        block->releaseLevel(level);
      }
    }
    if (!observed_left)
      result.emptied.push_back(block->key);
    else if (result.voxels_cleared > cleared_before)
      result.changed.push_back(block->key);
  }
  return result;
}

}  // namespace stereo_fusion
