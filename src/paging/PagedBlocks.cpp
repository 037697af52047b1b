#include "stereo_fusion/paging/PagedBlocks.h"

#include <algorithm>

namespace stereo_fusion {

void PagedBlocks::add(const BlockKey& key, const Entry& entry) {
  if (entries_.insert_or_assign(key, entry).second) regions_[regionOf(key)].push_back(key);
}

std::optional<PagedBlocks::Entry> PagedBlocks::remove(const BlockKey& key) {
  const auto it = entries_.find(key);
  if (it == entries_.end()) return std::nullopt;
  const Entry entry = it->second;
  entries_.erase(it);
  const auto region = regions_.find(regionOf(key));
  std::vector<BlockKey>& keys = region->second;
  keys.erase(std::find(keys.begin(), keys.end(), key));
  if (keys.empty()) regions_.erase(region);
  return entry;
}

void PagedBlocks::clear() {
  entries_.clear();
  regions_.clear();
}

void PagedBlocks::collect(const BlockBoxTest& may_contain, std::vector<BlockKey>* out) const {
  const size_t first = out->size();
  const double side = 1 << kRegionShift;
  for (const auto& [region, keys] : regions_) {
    const Eigen::Vector3d lo(region.x * side, region.y * side, region.z * side);
    if (!may_contain(lo, lo + Eigen::Vector3d::Constant(side))) continue;
    for (const BlockKey& key : keys) {
      const Eigen::Vector3d block_lo(key.x, key.y, key.z);
      if (may_contain(block_lo, block_lo + Eigen::Vector3d::Ones())) out->push_back(key);
    }
  }
  std::sort(out->begin() + first, out->end());
}

void PagedBlocks::collectAround(const std::vector<BlockKey>& keys,
                                std::vector<BlockKey>* out) const {
  if (entries_.empty()) return;
  const size_t first = out->size();
  for (const BlockKey& key : keys)
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const BlockKey near = key.offset(dx, dy, dz);
          if (entries_.count(near)) out->push_back(near);
        }
  std::sort(out->begin() + first, out->end());
  out->erase(std::unique(out->begin() + first, out->end()), out->end());
}

std::vector<BlockKey> PagedBlocks::sortedKeys() const {
  std::vector<BlockKey> keys;
  keys.reserve(entries_.size());
  for (const auto& [key, frame] : entries_) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  return keys;
}

}  // namespace stereo_fusion
