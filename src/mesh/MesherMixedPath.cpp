#include "MesherMixedPath.h"

#include <cstdint>

#include "MesherGeneralPath.h"
#include "MesherTables.h"
#include "MesherVoxelClasses.h"

namespace stereo_fusion::mesher {
namespace {

/// What the voxel masks tell about lattice points' samples before they are computed.
enum PointClass : uint8_t {
  kPointUnobserved = 0,   // a weighed voxel is unobserved or a touching block is absent
  kPointUndecided = 1,    // observed, sign not known without summing
  kPointNegative = 2,     // observed, every weighed voxel < −1e-30: each sum is < 0
  kPointNonNegative = 3,  // observed, every weighed voxel ≥ 0 (−0 included): each sum is ≥ 0
};

/// Per present block, bit masks over i of its own mesh level's row (j, k), built on first
/// use (rows_ready bit j + 8k); the same classes as the uniform path's row masks.
struct BlockMaskRows {
  // (No initialisers on the masks: a row is written before it is read, see rows_ready.)
  uint8_t unobserved[8][kFinestSide][kFinestSide];   // [d][k][j]
  uint8_t negative[8][kFinestSide][kFinestSide];     // [d][k][j], sdf < −1e-30
  uint8_t nonnegative[8][kFinestSide][kFinestSide];  // [d][k][j], sdf ≥ 0
  uint64_t rows_ready[8] = {};

  void ensureRow(const MesherContext& ctx, int d, int j, int k) {
    const uint64_t row_bit = uint64_t{1} << (j + kFinestSide * k);
    if (rows_ready[d] & row_bit) return;
    rows_ready[d] |= row_bit;
    const int side = levelSide(ctx.level[d]);
    const Voxel* row = ctx.voxels[d] + VoxelBlock::indexInLevel(side, 0, j, k);
    const VoxelClasses classes = classifyVoxels(row, side);
    unobserved[d][k][j] = static_cast<uint8_t>(classes.unobserved);
    negative[d][k][j] = static_cast<uint8_t>(classes.negative);
    nonnegative[d][k][j] = static_cast<uint8_t>(classes.nonnegative);
  }

  /// Bit i: the core box starting at owner centre (i, j, k) may yield triangles — its corner
  /// voxels are observed and change sign or lie too near 0 to classify (the owner's mask
  /// rows, as the uniform path's candidateStarts() does). A superset of the boxes
  /// coreBoxIsEmpty() keeps.
  unsigned coreCandidates(const MesherContext& ctx, int j, int k) {
    unsigned neg = 0, nonneg = 0, unobs = 0, unknown = 0;
    for (int dk = 0; dk < 2; ++dk)
      for (int dj = 0; dj < 2; ++dj) {
        ensureRow(ctx, 0, j + dj, k + dk);
        neg |= negative[0][k + dk][j + dj];
        nonneg |= nonnegative[0][k + dk][j + dj];
        unobs |= unobserved[0][k + dk][j + dj];
        unknown |= ~(negative[0][k + dk][j + dj] | nonnegative[0][k + dk][j + dj]) & 0xFFu;
      }
    const unsigned pairs =
        (((neg | (neg >> 1)) & (nonneg | (nonneg >> 1))) | unknown | (unknown >> 1)) &
        ~(unobs | (unobs >> 1));
    return pairs & ((1u << (levelSide(ctx.level[0]) - 1)) - 1);  // core boxes start at 0..side-2
  }

  /// What the voxel masks tell about the 8 corner samples of box [lo, hi] together: some
  /// corner unobserved, all certainly negative, all certainly non-negative, or undecided.
  /// Exact set algebra, no sampling: a block touching the box is incident to a product set
  /// of corners, so the voxels it weighs at them are the product of the per-axis unions of
  /// SupportIndexTable's index sets at lo and hi.
  PointClass classifyBoxCorners(const MesherContext& ctx, const int lo[3], const int hi[3]) {
    const SupportIndexTable& table = supportIndexTable();
    bool all_negative = true, all_nonnegative = true;
    for (unsigned blocks = incidentBlocks(lo, hi); blocks != 0; blocks &= blocks - 1) {
      const int d = __builtin_ctz(blocks), dx = d & 1, dy = (d >> 1) & 1, dz = d >> 2;
      if (ctx.nb[d] == nullptr) return kPointUnobserved;
      const auto& bits = table.bits[ctx.level[d]];
      const uint8_t is = bits[lo[0]][dx] | bits[hi[0]][dx];
      const uint8_t js = bits[lo[1]][dy] | bits[hi[1]][dy];
      const uint8_t ks = bits[lo[2]][dz] | bits[hi[2]][dz];
      for (unsigned kb = ks; kb != 0; kb &= kb - 1)
        for (unsigned jb = js; jb != 0; jb &= jb - 1) {
          const int j = __builtin_ctz(jb), k = __builtin_ctz(kb);
          ensureRow(ctx, d, j, k);
          if (unobserved[d][k][j] & is) return kPointUnobserved;
          all_negative &= (is & ~negative[d][k][j]) == 0;
          all_nonnegative &= (is & ~nonnegative[d][k][j]) == 0;
        }
    }
    return all_negative ? kPointNegative : (all_nonnegative ? kPointNonNegative : kPointUndecided);
  }

  /// True if the observed voxels that any point of the closed box [lo, hi] may weigh all
  /// share one sign (all < −1e-30, or all ≥ 0). Every sample meshBox() takes for the box —
  /// corners, hanging points, face-grid crossings — lies in the closed box and is a convex
  /// combination of such voxels, or unobserved; so the box yields nothing. This decides the
  /// boxes whose corners share one sign but which carry hanging points, without sampling.
  bool boxSupportHasOneSign(const MesherContext& ctx, const int lo[3], const int hi[3]) {
    const SupportIndexTable& table = supportIndexTable();
    bool all_negative = true, all_nonnegative = true;
    for (unsigned blocks = incidentBlocks(lo, hi); blocks != 0; blocks &= blocks - 1) {
      const int d = __builtin_ctz(blocks), dx = d & 1, dy = (d >> 1) & 1, dz = d >> 2;
      if (ctx.nb[d] == nullptr) continue;  // every point weighing an absent block is unobserved
      const auto& range = table.range[ctx.level[d]];
      const uint8_t is = range[lo[0]][hi[0]][dx];
      const uint8_t js = range[lo[1]][hi[1]][dy];
      const uint8_t ks = range[lo[2]][hi[2]][dz];
      for (unsigned kb = ks; kb != 0; kb &= kb - 1)
        for (unsigned jb = js; jb != 0; jb &= jb - 1) {
          const int j = __builtin_ctz(jb), k = __builtin_ctz(kb);
          ensureRow(ctx, d, j, k);
          const uint8_t observed = is & ~unobserved[d][k][j];
          all_negative &= (observed & ~negative[d][k][j]) == 0;
          all_nonnegative &= (observed & ~nonnegative[d][k][j]) == 0;
          if (!all_negative && !all_nonnegative) return false;
        }
    }
    return true;
  }
};

/// True if meshBox() would certainly add nothing for this box (an unobserved corner, a plain
/// box with one sign at all corners, or a box whose corners and every voxel its points may
/// weigh share one sign), decided on voxel bit masks without sampling; false when in doubt.
bool mixedBoxIsEmpty(const MesherContext& ctx, BlockMaskRows& masks, const int lo[3],
                     const int hi[3]) {
  // meshBox() returns without output at an unobserved corner, and on a plain box whose corners
  // share one sign; both are read off the voxel masks here without summing any sample. A box
  // with hanging points can change sign between its corners, unless every voxel its points
  // may weigh has the corners' sign (boxSupportHasOneSign()); otherwise meshBox() decides.
  switch (masks.classifyBoxCorners(ctx, lo, hi)) {
    case kPointUnobserved: return true;
    case kPointNegative:
    case kPointNonNegative:
      return boxIsPlain(ctx, lo, hi) || masks.boxSupportHasOneSign(ctx, lo, hi);
    default: return false;
  }
}

}  // namespace

void meshMixedBoxes(MesherContext& ctx) {
  ctx.buildLinePoints();
  BlockMaskRows masks;
  BoxIntervals intervals;
  for (int d = 0; d < 8; ++d) {
    if (ctx.nb[d] == nullptr) continue;
    intervals.build(d, ctx.step[d]);
    // The skin slab of each axis: the boxes in the last interval along it (the boxes touching
    // a block face lie in one). A box's support lies within its slab's: one sign there (or
    // nothing observed) and mixedBoxIsEmpty() would return true for each of them.
    const int* count = intervals.count;
    bool skin_is_empty[3];
    for (int a = 0; a < 3; ++a) {
      int lo[3], hi[3];
      for (int b = 0; b < 3; ++b) {
        lo[b] = intervals.bounds[b][a == b ? count[b] - 1 : 0].first;
        hi[b] = intervals.bounds[b][count[b] - 1].second;
      }
      skin_is_empty[a] = masks.boxSupportHasOneSign(ctx, lo, hi);
    }
    // Past the owner, the region is its skin along the axes of d.
    if (((d & 1) && skin_is_empty[0]) || ((d & 2) && skin_is_empty[1]) ||
        ((d & 4) && skin_is_empty[2]))
      continue;
    auto visit = [&](int ix, int iy, int iz) {
      const int lo[3] = {intervals.bounds[0][ix].first, intervals.bounds[1][iy].first,
                         intervals.bounds[2][iz].first};
      const int hi[3] = {intervals.bounds[0][ix].second, intervals.bounds[1][iy].second,
                         intervals.bounds[2][iz].second};
      const bool core = d == 0 && hi[0] < kBlockUnits && hi[1] < kBlockUnits && hi[2] < kBlockUnits;
      if (core) {
        // Most boxes: no voxel-level sign change. The exact corner signs decide here, so
        // the mask pre-test below could not reject a box that passes.
        if (ctx.coreBoxIsEmpty(lo)) return;
      } else if ((ix == count[0] - 1 && skin_is_empty[0]) ||
                 (iy == count[1] - 1 && skin_is_empty[1]) ||
                 (iz == count[2] - 1 && skin_is_empty[2]) || mixedBoxIsEmpty(ctx, masks, lo, hi)) {
        return;
      }
      meshBox(ctx, lo, hi);
    };
    for (int iz = 0; iz < count[2]; ++iz)
      for (int iy = 0; iy < count[1]; ++iy) {
        if (d == 0 && iy + 1 < count[1] && iz + 1 < count[2]) {
          // A row of core boxes and the skin box ending it: only the core boxes whose corners'
          // voxel masks allow a surface (coreCandidates()), in the same x order.
          for (unsigned bits = masks.coreCandidates(ctx, iy, iz); bits != 0; bits &= bits - 1)
            visit(__builtin_ctz(bits), iy, iz);
          visit(count[0] - 1, iy, iz);
          continue;
        }
        for (int ix = 0; ix < count[0]; ++ix) visit(ix, iy, iz);
      }
  }
}

}  // namespace stereo_fusion::mesher
