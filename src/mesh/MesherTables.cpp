#include "MesherTables.h"

#include <algorithm>

#include "stereo_fusion/mesh/CellPolygonizer.h"

namespace stereo_fusion::mesher {

CentreBitsTable::CentreBitsTable() {
  for (int level = 0; level < kNumLevels; ++level) bits[level] = centreBits(1 << level);
}

SupportIndexTable::SupportIndexTable() {
  for (int level = 0; level < kNumLevels; ++level) {
    const int step = 1 << level, side = levelSide(level), den = 2 * step;
    for (int q = 0; q < kAxisCoords; ++q)
      for (int offset = 0; offset < 2; ++offset) {
        int first, last;
        incidentRange(q, &first, &last);
        if (offset < first || offset > last) continue;
        // blockField()'s clamping: the last centre and beyond weigh voxel side-1 alone;
        // elsewhere a centre weighs one voxel and a point between centres two.
        const int num = std::clamp(q - kBlockUnits * offset - step, 0, (side - 1) * den);
        const int i0 = num / den;
        const bool between = num % den != 0;
        bits[level][q][offset] = static_cast<uint8_t>((1u << i0) | (between ? 2u << i0 : 0u));
      }
    for (int offset = 0; offset < 2; ++offset)
      for (int lo = 0; lo < kAxisCoords; ++lo) {
        uint8_t acc = 0;
        for (int hi = lo; hi < kAxisCoords; ++hi) {
          acc |= bits[level][hi][offset];
          range[level][lo][hi][offset] = acc;
        }
      }
  }
}

CrossingEdgeTable::CrossingEdgeTable() {
  for (int case_index = 0; case_index < 256; ++case_index)
    for (int e = 0; e < 12; ++e) {
      const mc::CubeEdge& edge = mc::cubeEdges()[e];
      if (((case_index >> edge.corner_a) ^ (case_index >> edge.corner_b)) & 1)
        edges[case_index] |= 1u << e;
    }
}

}  // namespace stereo_fusion::mesher
