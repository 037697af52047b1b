#pragma once
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "stereo_fusion/planning/EsdfPropagator.h"

namespace stereo_fusion {

/// What a planning block holds, as the transit rule reads it.
enum BlockKind : uint8_t { kHoldsOccupied = 1, kHoldsFree = 2 };
/// kHoldsOccupied if a cell is occupied, kHoldsFree if a known cell is not.
uint8_t blockKinds(const PlanningBlock& block);

/// The box around a block's occupied cells, around its free (known, not occupied) cells, and
/// the whole block's.
CellBox occupiedBox(const BlockKey& key, const PlanningBlock& block);
CellBox freeBox(const BlockKey& key, const PlanningBlock& block);
CellBox blockBox(const BlockKey& key);

/// Which blocks without a known cell the ESDF needs ("transit" blocks).
///
/// The wavefronts offer sites only through allocated blocks, so an obstacle that a free cell
/// sees across unknown space (a hole in the map between them) would not reach it, and the cell
/// would read too far. The rule: an absent block is allocated when it overlaps the convex hull
/// of the box around a block's occupied cells and the box around another block's free cells,
/// those cells within the max distance of each other. The straight line from each such occupied
/// cell to each such free cell, and the cells the wavefront takes along it, then lie in
/// allocated blocks: the site reaches the cell as if the map had no hole. Space behind a wall,
/// beside its free side but not between the wall and it, stays unallocated.
class EsdfTransit {
 public:
  explicit EsdfTransit(uint32_t max_dist2);

  /// Largest |offset| per axis, in blocks, between two blocks within reach of each other.
  int reachBlocks() const { return reach_; }
  /// Whether some cell of `a` and some cell of `b` lie within the max distance of each other.
  bool withinReach(const CellBox& a, const CellBox& b) const;
  /// Whether `c` overlaps the convex hull of `p` and `q` (by more than touching).
  static bool overlapsHull(const CellBox& c, const CellBox& p, const CellBox& q);

  /// Starts a pass: the blocks' cells may have changed since the previous one, so their
  /// summaries are recomputed when next read. Within a pass, only absent blocks may be added.
  void beginPass() { ++pass_; }
  /// The absent blocks that block `key` needs for the kinds it holds in `kinds`, between it and
  /// the blocks of the other kind within reach; sorted.
  std::vector<BlockKey> needed(const PlanningBlockMap& blocks, const BlockKey& key,
                               uint8_t kinds) const;

 private:
  /// `block`'s summary in this pass (computed on first read).
  const PlanningBlock& summarized(const BlockKey& key, const PlanningBlock& block) const;

  uint32_t max_dist2_;
  int reach_;
  std::vector<Eigen::Vector3i> offsets_;  ///< of the blocks within reach of a block, key order
  uint32_t pass_ = 1;
};

}  // namespace stereo_fusion
