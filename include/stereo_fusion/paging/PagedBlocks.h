#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fusion/map/BlockKey.h"

namespace stereo_fusion {

/// The index of the blocks paged out of memory (their pages are in the BlockStore): each key
/// with its last update frame (the eviction order needs it without reading the page) and
/// whether it has a submesh, grouped
/// by region of 8³ blocks so a query for the blocks near a camera tests regions first.
class PagedBlocks {
 public:
  struct Entry {
    uint64_t last_update_frame = 0;
    bool has_submesh = false;  ///< its page holds a submesh (the mesh's key set without reads)
  };
  static constexpr int kRegionShift = 3;  // a region is 8³ blocks

  void add(const BlockKey& key, const Entry& entry);
  /// Forgets `key`; its entry, or nullopt if it was not paged out.
  std::optional<Entry> remove(const BlockKey& key);
  bool contains(const BlockKey& key) const { return entries_.count(key) > 0; }
  size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  void clear();
  const std::unordered_map<BlockKey, Entry, BlockKeyHash>& entries() const { return entries_; }

  /// Box test in block coordinates: the box [lo, hi) of whole blocks (a block's own box, or a
  /// region's), in units of the block edge.
  using BlockBoxTest = std::function<bool(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi)>;
  /// Appends the paged keys whose box passes `may_contain`, testing each region's box first
  /// (`may_contain` must pass a region whenever it passes a block inside it). Sorted.
  void collect(const BlockBoxTest& may_contain, std::vector<BlockKey>* out) const;
  /// Appends the paged keys within one block (the 27 around and including) of any of `keys`.
  void collectAround(const std::vector<BlockKey>& keys, std::vector<BlockKey>* out) const;
  /// Every paged key, sorted.
  std::vector<BlockKey> sortedKeys() const;

 private:
  static BlockKey regionOf(const BlockKey& key) {
    return {key.x >> kRegionShift, key.y >> kRegionShift, key.z >> kRegionShift};
  }
  std::unordered_map<BlockKey, Entry, BlockKeyHash> entries_;
  std::unordered_map<BlockKey, std::vector<BlockKey>, BlockKeyHash> regions_;
};

}  // namespace stereo_fusion
