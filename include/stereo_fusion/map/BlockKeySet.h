#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "stereo_fusion/map/BlockKey.h"

namespace stereo_fusion {

/// A set of block keys for de-duplicating one pass's keys (a frame's blocks, a re-meshing's
/// owners), reused pass after pass: open addressing where each slot carries the generation of
/// the pass that wrote it, so starting a pass is O(1) instead of clearing the table.
class BlockKeySet {
 public:
  /// Empties the set and readies it for up to `max_keys` insertions.
  void reset(size_t max_keys) {
    size_t capacity = 64;
    while (capacity < 2 * max_keys) capacity *= 2;
    if (slots_.size() < capacity) {
      slots_.assign(capacity, Slot{});
      generation_ = 0;
    }
    if (++generation_ == 0) {  // wrapped: stale slots could look current
      std::fill(slots_.begin(), slots_.end(), Slot{});
      generation_ = 1;
    }
  }

  /// Adds `key`; true if it was not in the set yet. At most `max_keys` (reset()) insertions.
  bool insert(const BlockKey& key) {
    const size_t mask = slots_.size() - 1;
    for (size_t i = BlockKeyHash{}(key)&mask;; i = (i + 1) & mask) {
      Slot& slot = slots_[i];
      if (slot.generation != generation_) {
        slot = {key, generation_};
        return true;
      }
      if (slot.key == key) return false;
    }
  }

 private:
  struct Slot {
    BlockKey key;
    uint32_t generation = 0;  // in the set iff equal to generation_
  };
  std::vector<Slot> slots_;
  uint32_t generation_ = 0;
};

}  // namespace stereo_fusion
