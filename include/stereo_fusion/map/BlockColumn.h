#pragma once
#include <cstddef>
#include <vector>

#include "stereo_fusion/map/BlockOctree.h"

namespace stereo_fusion {

/// One value of type T per block of a map, owned by the stage that keeps it (the mesher's level
/// and sign bits, the eviction policy's last-update frame, a future layer's data), indexed by
/// the block's VoxelBlock::row. The map's topology knows nothing of it: adding a column adds
/// no field to VoxelBlock and touches no other stage.
///
/// Indices are reused after a block is erased: a stage writes a block's value whenever the
/// block is reported to it as updated (BlockChangeLog), which a new block always is, before it
/// reads it. fit() before reading rows of blocks allocated since the last fit().
template <typename T>
class BlockColumn {
 public:
  /// Grows to cover every row `map` has handed out; new entries are T{}.
  void fit(const BlockOctree& map) {
    if (values_.size() < map.rowCount()) values_.resize(map.rowCount());
  }
  T& operator[](const VoxelBlock& block) { return values_[block.row]; }
  const T& operator[](const VoxelBlock& block) const { return values_[block.row]; }
  size_t size() const { return values_.size(); }
  void clear() { values_.clear(); }

 private:
  std::vector<T> values_;
};

}  // namespace stereo_fusion
