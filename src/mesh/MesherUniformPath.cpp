#include "MesherUniformPath.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "MesherSurfaceVertex.h"
#include "MesherTables.h"
#include "MesherVoxelClasses.h"
#include "stereo_fusion/mesh/CellPolygonizer.h"

namespace stereo_fusion::mesher {
namespace {

// In a uniform neighbourhood (every present block at the owner's level) the voxel centres of
// the 8 blocks around the owner's high corner form one lattice, index 0..side-1 per axis for
// the owner's centres and `side` for the +neighbours' first centres. Every point a box samples
// is then an equal-weight average of 1, 2, 4 or 8 of these centres — the box's support, two
// consecutive indices per axis starting at the box's start index (a core box [c_i, c_i+1]
// starts at i; both skins around the face, [c_side-1, 16] and [16, 16 + s], start at side-1).
struct UniformLattice {
  // Bit i of a row mask describes the centre (i, j, k). (No initialisers: built per owner.)
  uint16_t row_negative[kFinestSide + 1][kFinestSide + 1];     // [k][j]
  uint16_t row_nonnegative[kFinestSide + 1][kFinestSide + 1];  // [k][j]
  uint16_t row_unobserved[kFinestSide + 1][kFinestSide + 1];   // [k][j], incl. absent blocks
  size_t corner_offset[8];  // box corner c's sample-grid slot − its low corner's
  float weight = 0.0f;      // every block's weight 1/s

  /// Fills the row masks. A centre counts as negative only when sdf < −1e-30, so that the
  /// weighted sums of samplePoint() cannot underflow to −0 (which compares as non-negative);
  /// centres nearer 0 are in neither mask and make their boxes candidates.
  void buildRowMasks(const MesherContext& ctx) {
    const int level = ctx.level[0];
    const int side = levelSide(level);
    const uint16_t row_bits = static_cast<uint16_t>((1u << side) - 1),
                   face_bit = static_cast<uint16_t>(1u << side);
    for (int k = 0; k <= side; ++k)
      for (int j = 0; j <= side; ++j) {
        // Centres 0..side-1 of the row come from one block, centre `side` from its +x neighbour.
        const int d = 2 * (j == side) + 4 * (k == side);
        const int block_j = j == side ? 0 : j, block_k = k == side ? 0 : k;
        VoxelClasses row;
        if (ctx.nb[d] != nullptr)
          row = classifyVoxels(&ctx.voxels[d][VoxelBlock::indexInLevel(side, 0, block_j, block_k)],
                               side);
        else
          row.unobserved = row_bits;
        if (ctx.nb[d + 1] != nullptr)
          classifyVoxelsScalar(
              &ctx.voxels[d + 1][VoxelBlock::indexInLevel(side, 0, block_j, block_k)], 1, side,
              &row);
        else
          row.unobserved |= face_bit;
        row_negative[k][j] = static_cast<uint16_t>(row.negative);
        row_nonnegative[k][j] = static_cast<uint16_t>(row.nonnegative);
        row_unobserved[k][j] = static_cast<uint16_t>(row.unobserved);
      }
  }

  /// Bit i set: the boxes starting at (i, j, k) may yield triangles. A clear bit means a
  /// support centre is unobserved (some corner is unobserved: meshBox() gives up) or the
  /// support has one sign (every corner, a convex combination of it, has that sign).
  uint16_t candidateStarts(int j, int k) const {
    // `unknown` per row, then combined: a centre near 0 in one row must not be hidden by a
    // classified centre of the same column in another row (that skipped boxes with a
    // corner in (−1e-30, 0) and both signs among their corners).
    uint16_t neg = 0, nonneg = 0, unobserved = 0, unknown = 0;  // unknown: near 0 (or unobserved)
    for (int dk = 0; dk < 2; ++dk)
      for (int dj = 0; dj < 2; ++dj) {
        neg |= row_negative[k + dk][j + dj];
        nonneg |= row_nonnegative[k + dk][j + dj];
        unobserved |= row_unobserved[k + dk][j + dj];
        unknown |= static_cast<uint16_t>(
            ~(row_negative[k + dk][j + dj] | row_nonnegative[k + dk][j + dj]));
      }
    // Over pairs (i, i+1): a candidate has no unobserved centre, and both signs or a centre
    // too near 0 to classify.
    const uint16_t pair_neg = neg | (neg >> 1), pair_nonneg = nonneg | (nonneg >> 1);
    const uint16_t pair_unknown = unknown | (unknown >> 1);
    const uint16_t pair_unobserved = unobserved | (unobserved >> 1);
    return static_cast<uint16_t>(((pair_neg & pair_nonneg) | pair_unknown) & ~pair_unobserved);
  }
};

/// samplePoint() for uniform neighbourhoods, reading the voxels by index. Every point a
/// uniform box uses is, per axis, an owner centre (one voxel), the block face (the last
/// centre below it and the first above) or the +neighbour's first centre; blockField()
/// returns exactly that voxel's value for each touching block (at most +0 instead of −0,
/// which `acc`, starting at +0, absorbs either way). The sums below are samplePoint()'s float
/// operations in its order (z, y, x outer to inner), so the result is the same bits. Here
/// every weight is w = 1/s and their sum n·w (n = 1, 2, 4, 8) is a power of two, so dividing
/// by it equals multiplying by its exact reciprocal (both round the same real number once).
bool sampleUniformPoint(const MesherContext& ctx, float w, const int q[3], PointSample* out) {
  const int level = ctx.level[0];
  const int shift = level + 1, side = levelSide(level);
  if (q[0] < kBlockUnits && q[1] < kBlockUnits && q[2] < kBlockUnits) {
    // An owner centre, the most common point: one voxel, the loop below unrolled.
    const Voxel& v = ctx.voxels[0][VoxelBlock::indexInLevel(side, (q[0] - ctx.step[0]) >> shift,
                                                            (q[1] - ctx.step[0]) >> shift,
                                                            (q[2] - ctx.step[0]) >> shift)];
    if (!(v.weight > 0.0f)) return false;
    // (0 + w·sdf) / w, as a product with 1/w = s; w·c / w for a colour byte c is c exactly.
    out->sdf = (0.0f + w * v.sdf_m) * static_cast<float>(ctx.step[0]);
    out->rgb[0] = static_cast<float>(v.r);
    out->rgb[1] = static_cast<float>(v.g);
    out->rgb[2] = static_cast<float>(v.b);
    return true;
  }
  // The blocks touching q in increasing d (samplePoint()'s z, y, x order), and per axis the
  // voxel index in the offset-0 block (offset-1 blocks are read at index 0).
  int low_index[3];
  for (int a = 0; a < 3; ++a)
    low_index[a] = q[a] >= kBlockUnits ? side - 1 : (q[a] - ctx.step[0]) >> shift;
  const int offset_index[2][3] = {{low_index[0], low_index[1] * side, low_index[2] * side * side},
                                  {0, 0, 0}};
  float weight_sum = 0.0f, acc = 0.0f, acc_rgb[3] = {0, 0, 0};
  for (unsigned blocks = incidentBlocks(q, q); blocks != 0; blocks &= blocks - 1) {
    const int d = __builtin_ctz(blocks);
    if (ctx.nb[d] == nullptr) return false;
    const Voxel& v = ctx.voxels[d][offset_index[d & 1][0] + offset_index[(d >> 1) & 1][1] +
                                   offset_index[d >> 2][2]];
    if (!(v.weight > 0.0f)) return false;
    weight_sum += w;
    acc += w * v.sdf_m;
    acc_rgb[0] += w * static_cast<float>(v.r);
    acc_rgb[1] += w * static_cast<float>(v.g);
    acc_rgb[2] += w * static_cast<float>(v.b);
  }
  const float inverse_weight_sum = 1.0f / weight_sum;  // exact: weight_sum is a power of two
  out->sdf = acc * inverse_weight_sum;
  for (int k = 0; k < 3; ++k) out->rgb[k] = acc_rgb[k] * inverse_weight_sum;
  return true;
}

/// The general path's meshBox() + its plain-box case for a uniform neighbourhood (every box
/// plain): corners by cache slot, only the crossing edges tested for the truncation band,
/// edges → vertices by slot.
void meshUniformBox(MesherContext& ctx, const UniformLattice& lattice, const int lo[3],
                    const int hi[3], const int grid_lo[3]) {
  MeshScratch& m = *ctx.scratch;
  const size_t base =
      grid_lo[0] +
      ctx.grid_dim[0] * (grid_lo[1] + static_cast<size_t>(ctx.grid_dim[1]) * grid_lo[2]);
  size_t slot[8];
  int case_index = 0;
  for (int c = 0; c < 8; ++c) {
    const size_t g = base + lattice.corner_offset[c];
    uint8_t& state = m.sample_state[g];
    if (state == kUnknown) {
      const int q[3] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]};
      state = sampleUniformPoint(ctx, lattice.weight, q, &m.samples[g]) ? kObserved : kUnobserved;
    }
    if (state != kObserved) return;
    slot[c] = g;
    case_index |= (m.samples[g].sdf >= 0.0f) << c;
  }
  if (case_index == 0 || case_index == 255) return;
  const auto& edges = mc::cubeEdges();
  for (unsigned bits = crossingEdgeTable().edges[case_index]; bits != 0; bits &= bits - 1) {
    const mc::CubeEdge& e = edges[__builtin_ctz(bits)];
    const float va = m.samples[slot[e.corner_a]].sdf, vb = m.samples[slot[e.corner_b]].sdf;
    if (std::min(std::abs(va), std::abs(vb)) >= ctx.truncated_abs) return;  // truncation-band edge
  }
  // First use of an edge comes first, as in the general path: vertices are numbered alike.
  for (const auto& tri : mc::caseTable().triangles[case_index]) {
    std::array<uint32_t, 3> t;
    for (int v = 0; v < 3; ++v) {
      const mc::CubeEdge& e = edges[tri[v]];
      const int axis = __builtin_ctz(static_cast<unsigned>(e.corner_a ^ e.corner_b));
      MeshScratch::EdgeVertex& entry = m.uniform_edge_vertex[3 * slot[e.corner_a] + axis];
      if (entry.stamp != m.uniform_edge_stamp) {
        // corner_a is the low end on `axis`: the canonical direction the general path uses.
        const int a[3] = {(e.corner_a & 1) ? hi[0] : lo[0], (e.corner_a & 2) ? hi[1] : lo[1],
                          (e.corner_a & 4) ? hi[2] : lo[2]};
        const int b[3] = {(e.corner_b & 1) ? hi[0] : lo[0], (e.corner_b & 2) ? hi[1] : lo[1],
                          (e.corner_b & 4) ? hi[2] : lo[2]};
        entry = {m.uniform_edge_stamp, static_cast<uint32_t>(ctx.out->positions.size())};
        appendVertex(ctx, a, m.samples[slot[e.corner_a]], b, m.samples[slot[e.corner_b]]);
      }
      t[v] = entry.vertex;
    }
    ctx.out->triangles.push_back(t);
  }
}

}  // namespace

void meshUniformBoxes(MesherContext& ctx) {
  UniformLattice lattice;
  lattice.buildRowMasks(ctx);
  lattice.weight = 1.0f / static_cast<float>(ctx.step[0]);
  const size_t stride_y = ctx.grid_dim[0], stride_z = stride_y * ctx.grid_dim[1];
  for (int c = 0; c < 8; ++c)
    lattice.corner_offset[c] = (c & 1) + ((c >> 1) & 1) * stride_y + (c >> 2) * stride_z;
  ctx.scratch->startUniformEdges(stride_z * ctx.grid_dim[2]);
  const int step = ctx.step[0], side = kFinestSide / step;
  // Box extents per axis by start index; the last start has two boxes (own skin, neighbour skin).
  // Grid indices (buildSampleGrid() on a uniform neighbourhood): centre i → i, the face →
  // side, the +neighbour's first centre → side + 1; a box's high index is its low one + 1.
  auto interval = [&](int start, bool neighbour_side, int* lo, int* hi, int* grid_lo) {
    if (neighbour_side) {
      *lo = kBlockUnits;
      *hi = kBlockUnits + step;
      *grid_lo = side;
    } else {
      *lo = step * (2 * start + 1);
      *hi = start + 1 < side ? step * (2 * start + 3) : kBlockUnits;
      *grid_lo = start;
    }
  };
  // Candidate starts per row, once: the blocks d below revisit the same rows (d = 0 and the
  // +x neighbour every row, the others the last rows).
  uint16_t candidates[kFinestSide][kFinestSide];  // [k][j]
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j) candidates[k][j] = lattice.candidateStarts(j, k);
  // Same box order as the general path (BoxIntervals): by block d, then z, y, x — the
  // submesh's vertex and triangle order does not depend on which path ran.
  for (int d = 0; d < 8; ++d) {
    if (ctx.nb[d] == nullptr) continue;
    int first[3], last[3];
    for (int a = 0; a < 3; ++a) {
      first[a] = (d >> a) & 1 ? side - 1 : 0;
      last[a] = side - 1;
    }
    const uint16_t x_range =
        static_cast<uint16_t>(((1u << (last[0] + 1)) - 1) & ~((1u << first[0]) - 1));
    for (int k = first[2]; k <= last[2]; ++k)
      for (int j = first[1]; j <= last[1]; ++j)
        for (uint16_t bits = candidates[k][j] & x_range; bits != 0; bits &= bits - 1) {
          const int i = __builtin_ctz(bits);
          int lo[3], hi[3], grid_lo[3];
          interval(i, d & 1, &lo[0], &hi[0], &grid_lo[0]);
          interval(j, (d >> 1) & 1, &lo[1], &hi[1], &grid_lo[1]);
          interval(k, (d >> 2) & 1, &lo[2], &hi[2], &grid_lo[2]);
          meshUniformBox(ctx, lattice, lo, hi, grid_lo);
        }
  }
}

}  // namespace stereo_fusion::mesher
