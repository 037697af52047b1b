#pragma once
#include <cstdint>
#include <cstddef>
#include <functional>
#include <ostream>

namespace stereo_fusion {

/// Integer coordinates of a voxel block: block (x, y, z) covers the world cube
/// [x, x+1) × [y, y+1) × [z, z+1) in units of the block edge length.
struct BlockKey {
  int32_t x = 0, y = 0, z = 0;

  friend bool operator==(const BlockKey& a, const BlockKey& b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
  }
  friend bool operator!=(const BlockKey& a, const BlockKey& b) { return !(a == b); }
  /// Lexicographic z, y, x: sorting by this order gives a deterministic, cache-friendly walk.
  friend bool operator<(const BlockKey& a, const BlockKey& b) {
    if (a.z != b.z) return a.z < b.z;
    if (a.y != b.y) return a.y < b.y;
    return a.x < b.x;
  }
  BlockKey offset(int dx, int dy, int dz) const { return {x + dx, y + dy, z + dz}; }
  friend std::ostream& operator<<(std::ostream& os, const BlockKey& k) {
    return os << "(" << k.x << ", " << k.y << ", " << k.z << ")";
  }
};

/// Component-wise minimum and maximum: the corners of the box around two keys.
inline BlockKey componentMin(const BlockKey& a, const BlockKey& b) {
  return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
inline BlockKey componentMax(const BlockKey& a, const BlockKey& b) {
  return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}

struct BlockKeyHash {
  size_t operator()(const BlockKey& k) const {
    // Large primes (Teschner et al. spatial hashing) spread neighbouring keys.
    return (static_cast<size_t>(static_cast<uint32_t>(k.x)) * 73856093u) ^
           (static_cast<size_t>(static_cast<uint32_t>(k.y)) * 19349663u) ^
           (static_cast<size_t>(static_cast<uint32_t>(k.z)) * 83492791u);
  }
};

}  // namespace stereo_fusion
