// The integer lattice BlockMesher works on (half-finest-voxel units; see BlockMesher.h,
// "Geometry") and the coordinate rules every meshing path shares, so that they agree on
// which blocks touch a point, which boxes an owner owns and how an edge is keyed.
#pragma once
#include <cstdint>
#include <utility>

#include "stereo_fusion/map/ResolutionLevel.h"

namespace stereo_fusion::mesher {

constexpr int kBlockUnits = 16;  // a block is 16 half-finest-voxel units wide
/// Lattice coordinates on one axis are 0..32 (owner 0..16, +neighbour 16..32).
constexpr int kAxisCoords = 2 * kBlockUnits + 1;
/// The highest coordinate a box reaches: the +neighbours' low skins end at their first
/// centre, 16 + step ≤ 16 + 4.
constexpr int kMaxBoxCoord = kBlockUnits + (1 << (kNumLevels - 1));

/// Offsets (0 or 1, relative to the owner) of the blocks touching coordinate q on one axis.
inline void incidentRange(int q, int* first, int* last) {
  *first = q > kBlockUnits ? 1 : 0;
  *last = q >= kBlockUnits ? 1 : 0;
}

/// Bit d set where block d has offset 1 on axis a.
inline constexpr unsigned kOffsetOne[3] = {0xAAu, 0xCCu, 0xF0u};

/// The blocks d (bit d) that points of the closed box [lo, hi] touch (incidentRange() per
/// axis), in increasing d: samplePoint()'s z, y, x order.
inline unsigned incidentBlocks(const int lo[3], const int hi[3]) {
  unsigned blocks = 0xFFu;
  for (int a = 0; a < 3; ++a) {
    if (lo[a] > kBlockUnits) blocks &= kOffsetOne[a];   // only offset 1 on this axis
    if (hi[a] < kBlockUnits) blocks &= ~kOffsetOne[a];  // only offset 0
  }
  return blocks;
}

inline uint64_t packPoint(const int q[3]) {
  return (static_cast<uint64_t>(q[0]) << 12) | (static_cast<uint64_t>(q[1]) << 6) |
         static_cast<uint64_t>(q[2]);
}

inline bool lexLess(const int a[3], const int b[3]) {
  if (a[0] != b[0]) return a[0] < b[0];
  if (a[1] != b[1]) return a[1] < b[1];
  return a[2] < b[2];
}

/// Bit c set: a block meshed with voxel step `step` has a voxel centre at local coordinate c.
inline uint64_t centreBits(int step) {
  uint64_t bits = 0;
  for (int c = step; c < kBlockUnits; c += 2 * step) bits |= uint64_t{1} << c;
  return bits;
}

/// The boxes an owner owns of block d (its own core and +side skins for d = 0, the low skins
/// of the +neighbours otherwise), as intervals [first, second] per axis: at most kFinestSide
/// per axis (fixed arrays: no allocation). Both box walks (general and mixed) visit them in
/// this order, so the submesh's vertex order does not depend on the path.
struct BoxIntervals {
  std::pair<int, int> bounds[3][kFinestSide];
  int count[3];

  /// The intervals of block d meshed with voxel step `step`.
  void build(int d, int step) {
    const int side = kFinestSide / step;
    for (int a = 0; a < 3; ++a) {
      int& n = count[a];
      n = 0;
      if ((d >> a) & 1) {
        bounds[a][n++] = {kBlockUnits, kBlockUnits + step};  // neighbour's low skin
      } else {
        for (int i = 0; i + 1 < side; ++i)
          bounds[a][n++] = {step * (2 * i + 1), step * (2 * i + 3)};
        bounds[a][n++] = {step * (2 * side - 1), kBlockUnits};  // own high skin
      }
    }
  }
};

}  // namespace stereo_fusion::mesher
