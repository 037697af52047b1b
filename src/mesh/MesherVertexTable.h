// The general path's edge → vertex map for one owner (the uniform path indexes its edges
// directly, MesherScratch.h).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace stereo_fusion::mesher {

/// Edge key → vertex index for one owner: open addressing over a power-of-two table. Slots
/// carry the stamp of the mesh() call that wrote them, so starting the next owner is O(1)
/// instead of freeing one hash node per vertex as std::unordered_map::clear() did.
class VertexTable {
 public:
  /// Forgets every entry (the next owner starts empty).
  void clear() {
    if (slots_.empty()) slots_.resize(kInitialSlots);
    if (++stamp_ == 0) {  // wrapped: stale stamps could match again
      for (Slot& slot : slots_) slot.stamp = 0;
      stamp_ = 1;
    }
    used_ = 0;
  }

  /// The vertex stored for `key`, or `next_vertex` after storing it (`*inserted` tells which).
  uint32_t findOrInsert(uint64_t key, uint32_t next_vertex, bool* inserted) {
    if (2 * (used_ + 1) > slots_.size()) grow();
    const size_t mask = slots_.size() - 1;
    for (size_t i = slotOf(key);; i = (i + 1) & mask) {
      Slot& slot = slots_[i];
      if (slot.stamp != stamp_) {
        slot = {key, next_vertex, stamp_};
        ++used_;
        *inserted = true;
        return next_vertex;
      }
      if (slot.key == key) {
        *inserted = false;
        return slot.vertex;
      }
    }
  }

 private:
  struct Slot {
    uint64_t key;
    uint32_t vertex;
    uint32_t stamp;  // entry is live iff stamp == stamp_
  };
  static constexpr size_t kInitialSlots = 1024;

  size_t slotOf(uint64_t key) const {
    // Fibonacci hashing: the top bits of the product mix all of the key's 36 bits.
    const int bits = __builtin_ctzll(slots_.size());
    return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - bits));
  }

  void grow() {
    std::vector<Slot> old(2 * slots_.size(), Slot{0, 0, 0});
    old.swap(slots_);
    const size_t mask = slots_.size() - 1;
    for (const Slot& slot : old) {
      if (slot.stamp != stamp_) continue;
      size_t i = slotOf(slot.key);
      while (slots_[i].stamp == stamp_) i = (i + 1) & mask;
      slots_[i] = slot;
    }
  }

  std::vector<Slot> slots_;
  uint32_t stamp_ = 0;
  size_t used_ = 0;
};

}  // namespace stereo_fusion::mesher
