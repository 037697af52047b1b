#pragma once
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "stereo_fusion/planning/PlanningBlock.h"

namespace stereo_fusion {

using PlanningBlockMap = std::unordered_map<BlockKey, std::unique_ptr<PlanningBlock>, BlockKeyHash>;

struct EsdfStats {
  uint64_t cells_flipped = 0;  ///< cells whose occupancy changed since the previous update
  uint64_t cells_raised = 0;   ///< cells whose site became invalid (raise wavefront)
  uint64_t cells_lowered = 0;  ///< cells given a nearer site (lower wavefront)
};

/// The Euclidean signed distance field over the planning blocks, kept by propagating sites
/// (Lau et al. 2013, in 3D over 26-neighbourhoods): every cell holds its site — the nearest
/// occupied cell for a cell that is not occupied, the nearest cell that is not occupied for an
/// occupied one — and its distance is the exact Euclidean distance to that site, |cell − site|
/// in cells (squared, integer: no rounding). Among sites at the same distance a cell keeps the
/// smallest in (z, y, x): the choice does not depend on the order of the offers, so an update
/// and a rebuild pick the same site — they must, since a distance reads its site's centre_sdf
/// (PlanningMap: sub-cell distances), and equally near sites carry different ones.
///
/// When cells flip (occupied ↔ not), a raise wavefront clears every cell whose site is no
/// longer of the opposite kind, then a lower wavefront (a priority queue by distance) offers
/// each cell's site, and the cell itself to its neighbours of the opposite kind, until no cell
/// improves. Sites are offered through allocated planning blocks only (unknown cells inside
/// them included: distances are geometric; EsdfTransit allocates the blocks a hole in the map
/// would otherwise cut); a cell beyond `max_dist2` cells² from any site keeps kNoSite (reads as
/// the max distance). Cells outside every block count as not occupied.
class EsdfPropagator {
 public:
  /// Brings `blocks` up to date after `flipped` cells changed occupancy and `fresh` blocks were
  /// allocated (their cells start without a site). Single-threaded, deterministic.
  EsdfStats update(PlanningBlockMap* blocks, const std::vector<CellIndex>& flipped,
                   const std::vector<BlockKey>& fresh, uint32_t max_dist2);
  /// Forgets every site and propagates from scratch.
  EsdfStats rebuild(PlanningBlockMap* blocks, uint32_t max_dist2);
};

/// Whether a cell is occupied (false outside every block).
bool cellOccupied(const PlanningBlockMap& blocks, const CellIndex& cell);

}  // namespace stereo_fusion
