#include "stereo_fusion/map/VoxelBlock.h"

#include <algorithm>

namespace stereo_fusion {

VoxelBlock::VoxelBlock(const VoxelBlock& other) { *this = other; }

VoxelBlock& VoxelBlock::operator=(const VoxelBlock& other) {
  if (this == &other) return *this;
  for (int l = 0; l < kNumLevels; ++l) {
    levels_[l].reset();
    if (other.levels_[l]) adoptLevel(l, other.levels_[l].get());
  }
  key = other.key;
  return *this;  // row and neighbours describe where the target sits in its octree: kept
}

const Voxel* VoxelBlock::unobservedLevel() {
  static const Voxel kUnobserved[levelVoxelCount(0)] = {};
  return kUnobserved;
}

Voxel* VoxelBlock::writableLevel(int level) {
  if (!levels_[level])
    levels_[level] =
        std::make_unique<Voxel[]>(levelVoxelCount(level));  // value-initialised: unobserved
  return levels_[level].get();
}

void VoxelBlock::adoptLevel(int level, const Voxel* voxels) {
  levels_[level].reset(new Voxel[levelVoxelCount(level)]);
  std::copy(voxels, voxels + levelVoxelCount(level), levels_[level].get());
}

void VoxelBlock::clearLevels() {
  for (auto& level : levels_) level.reset();
}

size_t VoxelBlock::voxelBytes() const {
  size_t bytes = 0;
  for (int l = 0; l < kNumLevels; ++l)
    if (levels_[l]) bytes += levelVoxelCount(l) * sizeof(Voxel);
  return bytes;
}

}  // namespace stereo_fusion
