#pragma once
// Brute-force distances over a PlanningBlockMap: what EsdfPropagator must reproduce.

#include <algorithm>
#include <cmath>
#include <vector>

#include "stereo_fusion/planning/EsdfPropagator.h"

namespace stereo_fusion::test {

/// Every cell of every block with its brute-force squared distance (cells²) to the nearest cell
/// of the other kind (occupied ↔ not, cells outside every block counting as not occupied),
/// PlanningBlock::kNoSite beyond `max_dist2`.
struct BruteForceCell {
  CellIndex cell;
  bool occupied;
  uint32_t dist2;
};

inline std::vector<BruteForceCell> bruteForceDistances(const PlanningBlockMap& blocks,
                                                       uint32_t max_dist2) {
  std::vector<CellIndex> occupied;
  std::vector<BruteForceCell> out;
  for (const auto& [key, block] : blocks)
    for (int c = 0; c < PlanningBlock::kCells; ++c) {
      const bool occ = PlanningBlock::test(block->occupied, c);
      out.push_back({cellOf(key, c), occ, PlanningBlock::kNoSite});
      if (occ) occupied.push_back(cellOf(key, c));
    }
  const int r = static_cast<int>(std::floor(std::sqrt(double(max_dist2))));
  for (BruteForceCell& b : out) {
    uint32_t best = PlanningBlock::kNoSite;
    if (b.occupied) {
      for (int dz = -r; dz <= r; ++dz)
        for (int dy = -r; dy <= r; ++dy)
          for (int dx = -r; dx <= r; ++dx) {
            const uint32_t d2 = dx * dx + dy * dy + dz * dz;
            if (d2 == 0 || d2 > max_dist2 || d2 >= best) continue;
            if (!cellOccupied(blocks, b.cell.offset(dx, dy, dz))) best = d2;
          }
    } else {
      for (const CellIndex& o : occupied) {
        const int64_t dx = o.x - b.cell.x, dy = o.y - b.cell.y, dz = o.z - b.cell.z;
        const int64_t d2 = dx * dx + dy * dy + dz * dz;
        if (d2 <= max_dist2 && d2 < best) best = static_cast<uint32_t>(d2);
      }
    }
    b.dist2 = best;
  }
  return out;
}

inline uint16_t storedDist2(const PlanningBlockMap& blocks, const CellIndex& cell) {
  return blocks.at(planningBlockOf(cell))->dist2[cellInBlock(cell)];
}

/// Largest |distance − brute force| in cells over every cell (kNoSite reads as √max_dist2).
inline double maxErrorCells(const PlanningBlockMap& blocks, uint32_t max_dist2) {
  double worst = 0.0;
  auto cells = [&](uint32_t d2) {
    return d2 == PlanningBlock::kNoSite ? std::sqrt(double(max_dist2)) : std::sqrt(double(d2));
  };
  for (const BruteForceCell& b : bruteForceDistances(blocks, max_dist2))
    worst = std::max(worst, std::abs(cells(storedDist2(blocks, b.cell)) - cells(b.dist2)));
  return worst;
}

}  // namespace stereo_fusion::test
