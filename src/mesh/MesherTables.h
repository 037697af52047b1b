// Tables the mesher reads per owner and box, computed once at first use (MesherTables.cpp):
// voxel centres per level, the voxels a lattice coordinate weighs, the crossing edges per
// marching-cubes case.
#pragma once
#include <cstdint>

#include "MesherLattice.h"

namespace stereo_fusion::mesher {

/// centreBits() per level (the mesher asks for them per owner and axis).
struct CentreBitsTable {
  uint64_t bits[kNumLevels];
  CentreBitsTable();
};

inline uint64_t levelCentreBits(int level) {
  static const CentreBitsTable table;
  return table.bits[level];
}

/// For a block at `level` whose offset on one axis is `offset` (0 or 1), the voxel indices
/// on that axis that blockField() weighs (non-zero weight) at lattice coordinate q, as a bit
/// mask; 0 when samplePoint() does not include that block at q (incidentRange()).
/// `range` is the union of `bits` over every coordinate of [lo, hi]: the voxels on that axis
/// that any point of a box spanning [lo, hi] may weigh.
struct SupportIndexTable {
  uint8_t bits[kNumLevels][kAxisCoords][2] = {};
  uint8_t range[kNumLevels][kAxisCoords][kAxisCoords][2] = {};  // [level][lo][hi][offset], lo ≤ hi
  SupportIndexTable();
};

inline const SupportIndexTable& supportIndexTable() {
  static const SupportIndexTable table;
  return table;
}

/// For each marching-cubes case, the cube edges whose corners differ in sign (bit e: edge e).
struct CrossingEdgeTable {
  uint16_t edges[256] = {};
  CrossingEdgeTable();
};

inline const CrossingEdgeTable& crossingEdgeTable() {
  static const CrossingEdgeTable table;
  return table;
}

}  // namespace stereo_fusion::mesher
