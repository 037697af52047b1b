#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstdint>

#include <Eigen/Core>

#include "stereo_fusion/map/BlockKey.h"

namespace stereo_fusion {

/// Integer coordinates of a planning cell: cell (x, y, z) covers [x, x+1) × [y, y+1) × [z, z+1)
/// in units of the cell edge (MapperConfig::planningCellSizeM()).
struct CellIndex {
  int32_t x = 0, y = 0, z = 0;
  friend bool operator==(const CellIndex& a, const CellIndex& b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
  }
  friend bool operator!=(const CellIndex& a, const CellIndex& b) { return !(a == b); }
  CellIndex offset(int dx, int dy, int dz) const { return {x + dx, y + dy, z + dz}; }
};

/// A box of cells in cell coordinates: cells min .. max − 1 on each axis (their extent).
struct CellBox {
  Eigen::Vector3i min = Eigen::Vector3i::Zero(), max = Eigen::Vector3i::Zero();
  bool empty() const { return (max.array() <= min.array()).any(); }
};

/// What the map knows of a cell.
enum class CellState : uint8_t {
  kUnknown = 0,  ///< never seen: neither a surface nor space a frame saw empty
  kFree = 1,     ///< seen empty (a ray passed through it short of its surface, or the TSDF's
                 ///< observed voxels in it all lie in front of a surface)
  kOccupied =
      2,  ///< holds a surface or the space just behind one (an observed TSDF voxel with sdf ≥ 0)
};

/// 8³ planning cells: the unit of allocation of the planning layer (its own sparse grid, keyed
/// like the TSDF's blocks but at the planning cell size). Bits per cell say what frames saw;
/// the ESDF fields hold each cell's nearest site (EsdfPropagator).
struct PlanningBlock {
  static constexpr int kSide = 8;
  static constexpr int kCells = kSide * kSide * kSide;
  using Bits = std::array<uint64_t, kCells / 64>;
  /// "No site within esdf_max_distance_m": the distance reads as that maximum.
  static constexpr uint16_t kNoSite = 0xFFFF;

  static constexpr int index(int i, int j, int k) { return i + kSide * (j + kSide * k); }
  static bool test(const Bits& bits, int cell) { return (bits[cell >> 6] >> (cell & 63)) & 1u; }
  static void set(Bits* bits, int cell, bool value) {
    const uint64_t mask = uint64_t{1} << (cell & 63);
    (*bits)[cell >> 6] = value ? ((*bits)[cell >> 6] | mask) : ((*bits)[cell >> 6] & ~mask);
  }
  static bool any(const Bits& bits) {
    for (uint64_t word : bits)
      if (word) return true;
    return false;
  }

  /// A frame saw the cell empty (FreeSpaceRecorder).
  Bits seen_free{};
  /// The TSDF holds an observed voxel in the cell (TsdfOccupancy).
  Bits tsdf_observed{};
  /// ... and the finest such level has one with sdf ≥ 0 (TsdfOccupancy).
  Bits occupied{};
  /// The TSDF's signed distance at the cell's centre (TsdfOccupancy: > 0 behind the surface), in
  /// units of cell / kCentreSdfScale, clamped to ± half a cell (the farthest a surface that
  /// crosses the cell square-on lies from its centre: projective and noisy distances beyond it
  /// are not the cell's own surface); 0 where the TSDF holds none. A site's value moves the
  /// distances read from it off the cell centres onto the surface (sub-cell).
  std::array<int8_t, kCells> centre_sdf{};
  static constexpr float kCentreSdfScale = 254.0f;  // ±0.5 cell ↔ ±127
  static int8_t quantizeCentreSdf(float sdf_m, double cell_m) {
    if (!std::isfinite(sdf_m)) return 0;
    const double units = std::clamp(sdf_m / cell_m, -0.5, 0.5) * kCentreSdfScale;
    return static_cast<int8_t>(std::lround(units));
  }
  double centreSdfM(int cell, double cell_m) const {
    return centre_sdf[cell] * cell_m / kCentreSdfScale;
  }
  /// ESDF (EsdfPropagator): per cell the squared distance, in cells², to its site — the nearest
  /// occupied cell for a cell that is not occupied, the nearest cell that is not for an
  /// occupied one — and the site as an offset from the cell; kNoSite beyond the max distance.
  std::array<uint16_t, kCells> dist2;
  std::array<std::array<int8_t, 3>, kCells> site;
  /// The boxes around the occupied and the free cells the transit rule last acted on (empty:
  /// never), and whether the block waits for it to act again (its free box grew since).
  CellBox rule_occupied_box, rule_free_box;
  bool rule_queued = false;
  /// The transit rule's summary of the block — its kinds and the boxes around its occupied and
  /// its free cells — valid while `summary_pass` is the rule's current pass (EsdfTransit).
  mutable uint32_t summary_pass = 0;
  mutable uint8_t summary_kinds = 0;
  mutable CellBox summary_occupied, summary_free;

  PlanningBlock() { dist2.fill(kNoSite); }

  bool known(int cell) const { return test(seen_free, cell) || test(tsdf_observed, cell); }
  bool anyKnown() const {
    for (size_t w = 0; w < seen_free.size(); ++w)
      if (seen_free[w] | tsdf_observed[w]) return true;
    return false;
  }
  CellState state(int cell) const {
    if (test(occupied, cell)) return CellState::kOccupied;
    return known(cell) ? CellState::kFree : CellState::kUnknown;
  }
};

inline int32_t floorDiv(int32_t a, int32_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

/// The planning block holding `cell`, and the cell's index inside it.
inline BlockKey planningBlockOf(const CellIndex& cell) {
  return {floorDiv(cell.x, PlanningBlock::kSide), floorDiv(cell.y, PlanningBlock::kSide),
          floorDiv(cell.z, PlanningBlock::kSide)};
}
inline int cellInBlock(const CellIndex& cell) {
  auto local = [](int32_t v) {
    return v - PlanningBlock::kSide * floorDiv(v, PlanningBlock::kSide);
  };
  return PlanningBlock::index(local(cell.x), local(cell.y), local(cell.z));
}
inline CellIndex cellOf(const BlockKey& block, int cell) {
  const int s = PlanningBlock::kSide;
  return {block.x * s + cell % s, block.y * s + (cell / s) % s, block.z * s + cell / (s * s)};
}

/// The planning grid's range: cells within ±kPlanningCellLimit on each axis
/// (PlanningGrid::cellFor), so planning block keys within ±kPlanningCellLimit / 8 — 8× fewer than
/// the TSDF's keys reach.
constexpr int32_t kPlanningCellLimit = int32_t{1} << 28;
inline bool planningBlockKeyInRange(const BlockKey& key) {
  constexpr int32_t limit = kPlanningCellLimit / PlanningBlock::kSide;
  return std::abs(key.x) < limit && std::abs(key.y) < limit && std::abs(key.z) < limit;
}

/// Cell geometry: world point ↔ cell.
struct PlanningGrid {
  double cell_m = 0.08;
  /// The cell holding `p_world`; false if it lies beyond the grid's range (±2²⁸ cells) or is
  /// not finite.
  bool cellFor(const Eigen::Vector3d& p_world, CellIndex* cell) const {
    const double limit = static_cast<double>(kPlanningCellLimit);
    int32_t c[3];
    for (int a = 0; a < 3; ++a) {
      const double v = std::floor(p_world[a] / cell_m);
      if (!(std::abs(v) < limit)) return false;
      c[a] = static_cast<int32_t>(v);
    }
    *cell = {c[0], c[1], c[2]};
    return true;
  }
  Eigen::Vector3d centre(const CellIndex& cell) const {
    return {(cell.x + 0.5) * cell_m, (cell.y + 0.5) * cell_m, (cell.z + 0.5) * cell_m};
  }
  double blockM() const { return cell_m * PlanningBlock::kSide; }
};

}  // namespace stereo_fusion
