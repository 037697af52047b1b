#include "stereo_fusion/mesh/BlockMesher.h"
#include "stereo_fusion/map/TruncationBand.h"

#include <algorithm>
#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#if defined(__SSE4_1__)
#include <smmintrin.h>
#endif

#include "stereo_fusion/mesh/CellPolygonizer.h"

namespace stereo_fusion {

namespace {
constexpr int kBlockUnits = 16;  // a block is 16 half-finest-voxel units wide

/// Offsets (0 or 1, relative to the owner) of the blocks touching coordinate q on one axis.
inline void incidentRange(int q, int* first, int* last) {
  *first = q > kBlockUnits ? 1 : 0;
  *last = q >= kBlockUnits ? 1 : 0;
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

/// Trilinear interpolation of one block's voxels of `level` (`voxels`: levelVoxelCount(level)
/// of them, VoxelBlock::index() order) at block-local lattice coordinates (0..16, in half
/// finest voxels), clamped to the block's voxel centres. False if a sample that contributes is
/// unobserved.
bool blockField(const Voxel* voxels, int level, const int local[3], float* sdf, float rgb[3]) {
  const int step = 1 << level;
  const int side = kFinestSide >> level;
  // Centres are `den` = 2·step apart: shifts and masks instead of integer division (the
  // operands below are non-negative where divided, so the results are the same).
  const int den = 2 * step;
  const int shift = level + 1;
  const int mask = den - 1;
  // Most points are voxel centres: read the voxel (what the interpolation below yields).
  if (((local[0] - step) & mask) == 0 && ((local[1] - step) & mask) == 0 && ((local[2] - step) & mask) == 0 &&
      local[0] > 0 && local[1] > 0 && local[2] > 0 && local[0] < kBlockUnits &&
      local[1] < kBlockUnits && local[2] < kBlockUnits) {
    const Voxel& v = voxels[VoxelBlock::indexInLevel(side, (local[0] - step) >> shift, (local[1] - step) >> shift,
                                                     (local[2] - step) >> shift)];
    if (!(v.weight > 0.0f)) return false;
    *sdf = v.sdf_m;
    rgb[0] = v.r;
    rgb[1] = v.g;
    rgb[2] = v.b;
    return true;
  }
  int i0[3];
  float frac[3];
  for (int a = 0; a < 3; ++a) {
    const int num = std::clamp(local[a] - step, 0, (side - 1) * den);
    i0[a] = num >> shift;
    int rem = num & mask;
    if (i0[a] == side - 1) {  // on the last centre: use the last cell with fraction 1
      i0[a] = side - 2;
      rem = den;
    }
    frac[a] = static_cast<float>(rem) / static_cast<float>(den);
  }
  // On centre planes in every axis (block faces clamp to the outer centres): one voxel with
  // weight 1. The sums start at +0 as in the loop below, so −0 reads as +0 there too.
  if ((frac[0] == 0.0f || frac[0] == 1.0f) && (frac[1] == 0.0f || frac[1] == 1.0f) &&
      (frac[2] == 0.0f || frac[2] == 1.0f)) {
    const Voxel& v = voxels[VoxelBlock::indexInLevel(side, i0[0] + (frac[0] == 1.0f), i0[1] + (frac[1] == 1.0f),
                                                     i0[2] + (frac[2] == 1.0f))];
    if (!(v.weight > 0.0f)) return false;
    *sdf = 0.0f + v.sdf_m;
    rgb[0] = 0.0f + v.r;
    rgb[1] = 0.0f + v.g;
    rgb[2] = 0.0f + v.b;
    return true;
  }
  return trilinearVoxels(voxels, side, i0, frac, sdf, rgb);
}

/// Lattice coordinates on one axis are 0..32 (owner 0..16, +neighbour 16..32).
constexpr int kAxisCoords = 2 * kBlockUnits + 1;
/// The highest coordinate a box reaches: the +neighbours' low skins end at their first
/// centre, 16 + step ≤ 16 + 4.
constexpr int kMaxBoxCoord = kBlockUnits + (1 << (kNumLevels - 1));

/// Bit c set: a block meshed with voxel step `step` has a voxel centre at local coordinate c.
inline uint64_t centreBits(int step) {
  uint64_t bits = 0;
  for (int c = step; c < kBlockUnits; c += 2 * step) bits |= uint64_t{1} << c;
  return bits;
}

/// centreBits() per level, computed once (the mesher asks for them per owner and axis).
struct CentreBitsTable {
  uint64_t bits[kNumLevels];
  CentreBitsTable() {
    for (int level = 0; level < kNumLevels; ++level) bits[level] = centreBits(1 << level);
  }
};

inline uint64_t levelCentreBits(int level) {
  static const CentreBitsTable table;
  return table.bits[level];
}

/// Sign classes of a run of voxels as bit masks (bit i: voxel i): unobserved (!(weight > 0)),
/// observed with sdf ≥ 0, observed with sdf < −1e-30 (near-zero negatives in neither: the
/// mesher's weighted sums can round them to −0).
struct VoxelClasses {
  unsigned negative = 0, nonnegative = 0, unobserved = 0;
};

inline void classifyVoxelsScalar(const Voxel* voxels, int count, int first_bit, VoxelClasses* out) {
  for (int i = 0; i < count; ++i) {
    const bool observed = voxels[i].weight > 0.0f;
    out->unobserved |= static_cast<unsigned>(!observed) << (first_bit + i);
    out->nonnegative |= static_cast<unsigned>(observed && voxels[i].sdf_m >= 0.0f) << (first_bit + i);
    out->negative |= static_cast<unsigned>(observed && voxels[i].sdf_m < -1e-30f) << (first_bit + i);
  }
}

/// classifyVoxelsScalar() for `count` voxels (a row of any level: 1, 2, 4 or 8). Every mesh()
/// classifies a few hundred voxels, so rows of 4 and 8 go 4 at a time through SSE (part of the
/// x86-64-v2 baseline the project builds for): the same ordered comparisons, NaN false alike.
inline VoxelClasses classifyVoxels(const Voxel* voxels, int count) {
  VoxelClasses out;
#if defined(__SSE4_1__)
  static_assert(sizeof(Voxel) == 12 && offsetof(Voxel, sdf_m) == 0 && offsetof(Voxel, weight) == 4,
                "the shuffles below assume {sdf, weight, colour} in 12 bytes");
  if (count % 4 == 0) {
    const __m128 zero = _mm_setzero_ps(), tiny_negative = _mm_set1_ps(-1e-30f);
    for (int first = 0; first < count; first += 4) {
      // 4 voxels = 12 floats: s0 w0 c0 s1 | w1 c1 s2 w2 | c2 s3 w3 c3.
      const float* f = &voxels[first].sdf_m;
      const __m128 a = _mm_loadu_ps(f), b = _mm_loadu_ps(f + 4), c = _mm_loadu_ps(f + 8);
      const __m128 sdf = _mm_insert_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 2, 3, 0)), c, (1 << 6) | (3 << 4));
      const __m128 w123 = _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 0));              // w1 w2 w3 w3
      const __m128 w0011 = _mm_shuffle_ps(a, w123, _MM_SHUFFLE(0, 0, 1, 1));          // w0 w0 w1 w1
      const __m128 weight = _mm_shuffle_ps(w0011, w123, _MM_SHUFFLE(2, 1, 2, 0));     // w0 w1 w2 w3
      const __m128 observed = _mm_cmpgt_ps(weight, zero);
      const unsigned observed_bits = static_cast<unsigned>(_mm_movemask_ps(observed));
      out.unobserved |= (~observed_bits & 0xFu) << first;
      out.nonnegative |= static_cast<unsigned>(_mm_movemask_ps(_mm_and_ps(observed, _mm_cmpge_ps(sdf, zero)))) << first;
      out.negative |= static_cast<unsigned>(_mm_movemask_ps(_mm_and_ps(observed, _mm_cmplt_ps(sdf, tiny_negative))))
                      << first;
    }
    return out;
  }
#endif
  classifyVoxelsScalar(voxels, count, 0, &out);
  return out;
}

enum SampleState : uint8_t { kUnknown = 0, kObserved = 1, kUnobserved = 2 };

/// For a block at `level` whose offset on one axis is `offset` (0 or 1), the voxel indices
/// on that axis that blockField() weighs (non-zero weight) at lattice coordinate q, as a bit
/// mask; 0 when samplePoint() does not include that block at q (incidentRange()).
/// `range` is the union of `bits` over every coordinate of [lo, hi]: the voxels on that axis
/// that any point of a box spanning [lo, hi] may weigh.
struct SupportIndexTable {
  uint8_t bits[kNumLevels][kAxisCoords][2] = {};
  uint8_t range[kNumLevels][kAxisCoords][kAxisCoords][2] = {};  // [level][lo][hi][offset], lo ≤ hi

  SupportIndexTable() {
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
};

const SupportIndexTable& supportIndexTable() {
  static const SupportIndexTable table;
  return table;
}

/// What the voxel masks tell about lattice points' samples before they are computed.
enum PointClass : uint8_t {
  kPointUnobserved = 0,   // a weighed voxel is unobserved or a touching block is absent
  kPointUndecided = 1,    // observed, sign not known without summing
  kPointNegative = 2,     // observed, every weighed voxel < −1e-30: each sum is < 0
  kPointNonNegative = 3,  // observed, every weighed voxel ≥ 0 (−0 included): each sum is ≥ 0
};

/// Edge key → vertex index for one owner: open addressing over a power-of-two table. Slots
/// carry the stamp of the mesh() call that wrote them, so starting the next owner is O(1)
/// instead of freeing one hash node per vertex as std::unordered_map::clear() did.
class VertexTable {
 public:
  /// Forgets every entry (the next owner starts empty).
  void clear() {
    if (slots_.empty()) slots_.resize(kInitialSlots);
    if (++stamp_ == 0) {  // wrapped: stale stamps could match again
      for (Slot& slot : slots_) slot.stamp = 0;
      stamp_ = 1;
    }
    used_ = 0;
  }

  /// The vertex stored for `key`, or `next_vertex` after storing it (`*inserted` tells which).
  uint32_t findOrInsert(uint64_t key, uint32_t next_vertex, bool* inserted) {
    if (2 * (used_ + 1) > slots_.size()) grow();
    const size_t mask = slots_.size() - 1;
    for (size_t i = slotOf(key);; i = (i + 1) & mask) {
      Slot& slot = slots_[i];
      if (slot.stamp != stamp_) {
        slot = {key, next_vertex, stamp_};
        ++used_;
        *inserted = true;
        return next_vertex;
      }
      if (slot.key == key) {
        *inserted = false;
        return slot.vertex;
      }
    }
  }

 private:
  struct Slot {
    uint64_t key;
    uint32_t vertex;
    uint32_t stamp;  // entry is live iff stamp == stamp_
  };
  static constexpr size_t kInitialSlots = 1024;

  size_t slotOf(uint64_t key) const {
    // Fibonacci hashing: the top bits of the product mix all of the key's 36 bits.
    const int bits = __builtin_ctzll(slots_.size());
    return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - bits));
  }

  void grow() {
    std::vector<Slot> old(2 * slots_.size(), Slot{0, 0, 0});
    old.swap(slots_);
    const size_t mask = slots_.size() - 1;
    for (const Slot& slot : old) {
      if (slot.stamp != stamp_) continue;
      size_t i = slotOf(slot.key);
      while (slots_[i].stamp == stamp_) i = (i + 1) & mask;
      slots_[i] = slot;
    }
  }

  std::vector<Slot> slots_;
  uint32_t stamp_ = 0;
  size_t used_ = 0;
};

/// Per-thread buffers reused across mesh() calls, so the hot path does not allocate.
struct MeshScratch {
  std::vector<Voxel> seam_fills[8];            // face-filled copies of the neighbourhood's blocks
  std::vector<uint8_t> sample_state;           // SampleState per lattice grid point
  std::vector<BlockMesher::PointSample> samples;  // per grid point, valid when kObserved
  // Generic-box scratch.
  std::vector<std::array<int, 3>> points;
  std::vector<std::vector<int>> polygons;  // only the first `polygon_count` are in use
  std::vector<int> grid_u, grid_v, lines, hanging;
  std::vector<float> values;
  std::vector<std::array<mc::Crossing, 3>> triangles;
  VertexTable vertex_of;
  // Uniform neighbourhoods: every box edge joins grid points one index apart on one axis, so
  // edge (grid point g, axis a) → slot 3g + a replaces hashing. A slot is live iff its stamp
  // is `uniform_edge_stamp` (bumped per owner, so no clearing).
  struct EdgeVertex {
    uint32_t stamp;
    uint32_t vertex;
  };
  std::vector<EdgeVertex> uniform_edge_vertex;
  uint32_t uniform_edge_stamp = 0;

  /// Readies uniform_edge_vertex for an owner whose sample grid has `points` points.
  void startUniformEdges(size_t points) {
    if (uniform_edge_vertex.size() < 3 * points) uniform_edge_vertex.resize(3 * points, EdgeVertex{0, 0});
    if (++uniform_edge_stamp == 0) {  // wrapped: stale stamps could match again
      for (EdgeVertex& slot : uniform_edge_vertex) slot.stamp = 0;
      uniform_edge_stamp = 1;
    }
  }
};

/// For each marching-cubes case, the cube edges whose corners differ in sign (bit e: edge e).
struct CrossingEdgeTable {
  uint16_t edges[256] = {};

  CrossingEdgeTable() {
    for (int case_index = 0; case_index < 256; ++case_index)
      for (int e = 0; e < 12; ++e) {
        const mc::CubeEdge& edge = mc::cubeEdges()[e];
        if (((case_index >> edge.corner_a) ^ (case_index >> edge.corner_b)) & 1) edges[case_index] |= 1u << e;
      }
  }
};

const CrossingEdgeTable& crossingEdgeTable() {
  static const CrossingEdgeTable table;
  return table;
}
}  // namespace

struct BlockMesher::Context {
  const VoxelBlock* nb[8] = {};  // owner + (d & 1, (d >> 1) & 1, (d >> 2) & 1)
  const Voxel* voxels[8] = {};   // what the mesher samples of nb[d]: meshVoxels()
  int level[8] = {};
  int step[8] = {};
  bool uniform = true;  // every present neighbour has the owner's level
  float truncated_abs = 0.0f;  // 0.99 · Φ of the coarsest level present
  int64_t origin[3] = {};
  double unit = 0.0;
  SubMesh* out = nullptr;
  MeshScratch* scratch = nullptr;
  VertexTable* vertex_of = nullptr;                              // edge → vertex, per owner
  std::vector<PointSample>* vertex_samples = nullptr;            // generic-box scratch
  // Sample cache. Every point the mesher samples is a block face coordinate (16) or a voxel
  // centre of a present block on each axis; those coordinates get a dense grid index so
  // that each point is sampled once per owner instead of once per box using it.
  // (The arrays below have no initialisers: each is filled before it is read, and zeroing
  // ~2 KiB per owner showed up in the profile.)
  int8_t grid_index[3][kAxisCoords];  // −1: coordinate not in the grid
  int grid_coords[3][kAxisCoords];     // grid index → coordinate, ascending
  int grid_dim[3] = {};
  size_t uniform_corner_offset[8];  // uniform neighbourhoods: box corner c's slot − its low corner's
  float uniform_weight = 0.0f;      // uniform neighbourhoods: every block's weight 1/s
  // Lattice points on lines along each axis, as bit masks over the coordinate u (bit u set:
  // a present block touching the line has a voxel centre at u). Indexed [axis][class of the
  // next axis' coordinate][class of the one after][u ≥ 16], class 0 below the block face
  // (only offset-0 blocks touch), 1 on it (both), 2 above (only offset-1 blocks).
  uint64_t line_points[3][3][3][2];

  void buildLinePoints() {
    for (int axis = 0; axis < 3; ++axis)
      for (int ca = 0; ca < 3; ++ca)
        for (int cb = 0; cb < 3; ++cb)
          for (int du = 0; du < 2; ++du) {
            uint64_t bits = 0;
            for (int oa = ca == 2 ? 1 : 0; oa <= (ca >= 1 ? 1 : 0); ++oa)
              for (int ob = cb == 2 ? 1 : 0; ob <= (cb >= 1 ? 1 : 0); ++ob) {
                int off[3];
                off[axis] = du;
                off[(axis + 1) % 3] = oa;
                off[(axis + 2) % 3] = ob;
                const int d = off[0] + 2 * off[1] + 4 * off[2];
                if (nb[d] == nullptr) continue;
                bits |= levelCentreBits(level[d]) << (kBlockUnits * du);
              }
            line_points[axis][ca][cb][du] = bits;
          }
  }

  /// The lattice points strictly inside (u0, u1) on the line along `axis` through `fixed`
  /// (the segment lies on one side of the block face: u0 ≥ 16 or u1 ≤ 16).
  uint64_t hangingBits(int axis, const int fixed[3], int u0, int u1) const {
    auto cls = [](int q) { return q < kBlockUnits ? 0 : (q == kBlockUnits ? 1 : 2); };
    const uint64_t line = line_points[axis][cls(fixed[(axis + 1) % 3])][cls(fixed[(axis + 2) % 3])][u0 >= kBlockUnits];
    const uint64_t inside = ((uint64_t{1} << u1) - 1) & ~((uint64_t{2} << u0) - 1);
    return line & inside;
  }

  bool coreBoxIsEmpty(const int lo[3]) const {
    const int level = this->level[0], shift = level + 1;
    const int i = (lo[0] - step[0]) >> shift, j = (lo[1] - step[0]) >> shift, k = (lo[2] - step[0]) >> shift;
    const float w = 1.0f / static_cast<float>(step[0]);
    bool any_negative = false, any_nonnegative = false;
    for (int c = 0; c < 8; ++c) {
      const Voxel& v =
          voxels[0][VoxelBlock::indexInLevel(levelSide(level), i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2))];
      if (!(v.weight > 0.0f)) return true;
      // samplePoint() yields (0 + w·sdf) / w; dividing by w > 0 (≤ 1) keeps the sign and
      // cannot underflow, and 0 + x ≥ 0 iff x ≥ 0: the sign of w·sdf is the sample's.
      (w * v.sdf_m >= 0.0f ? any_nonnegative : any_negative) = true;
    }
    return !(any_negative && any_nonnegative);
  }

  /// Bit i: the core box starting at owner centre (i, j, k) may yield triangles — its corner
  /// voxels are observed and change sign or lie too near 0 to classify (the owner's mask
  /// rows, as candidateStarts() does for uniform neighbourhoods). A superset of the boxes
  /// coreBoxIsEmpty() keeps.
  unsigned coreCandidates(int j, int k) {
    unsigned neg = 0, nonneg = 0, unobserved = 0, unknown = 0;
    for (int dk = 0; dk < 2; ++dk)
      for (int dj = 0; dj < 2; ++dj) {
        ensureMaskRow(0, j + dj, k + dk);
        neg |= mask_negative[0][k + dk][j + dj];
        nonneg |= mask_nonnegative[0][k + dk][j + dj];
        unobserved |= mask_unobserved[0][k + dk][j + dj];
        unknown |= ~(mask_negative[0][k + dk][j + dj] | mask_nonnegative[0][k + dk][j + dj]) & 0xFFu;
      }
    const unsigned pairs = (((neg | (neg >> 1)) & (nonneg | (nonneg >> 1))) | unknown | (unknown >> 1)) &
                           ~(unobserved | (unobserved >> 1));
    return pairs & ((1u << (levelSide(level[0]) - 1)) - 1);  // core boxes start at 0..side-2
  }

  // Uniform neighbourhoods (every present block at the owner's level): the voxel centres of
  // the 8 blocks around the owner's high corner form one lattice, index 0..side-1 per axis
  // for the owner's centres and `side` for the +neighbours' first centres. Every point a box
  // samples is then an equal-weight average of 1, 2, 4 or 8 of these centres — the box's
  // support, two consecutive indices per axis starting at the box's start index (a core box
  // [c_i, c_i+1] starts at i; both skins around the face, [c_side-1, 16] and [16, 16 + s],
  // start at side-1). Bit i of a row mask describes the centre (i, j, k).
  uint16_t row_negative[kFinestSide + 1][kFinestSide + 1];     // [k][j]
  uint16_t row_nonnegative[kFinestSide + 1][kFinestSide + 1];  // [k][j]
  uint16_t row_unobserved[kFinestSide + 1][kFinestSide + 1];   // [k][j], incl. absent blocks

  /// Fills the row masks (uniform neighbourhoods only). A centre counts as negative only when
  /// sdf < −1e-30, so that the weighted sums of samplePoint() cannot underflow to −0 (which
  /// compares as non-negative); centres nearer 0 are in neither mask and make their boxes
  /// candidates.
  void buildRowMasks() {
    const int level = this->level[0];
    const int side = levelSide(level);
    const uint16_t row_bits = static_cast<uint16_t>((1u << side) - 1), face_bit = static_cast<uint16_t>(1u << side);
    for (int k = 0; k <= side; ++k)
      for (int j = 0; j <= side; ++j) {
        // Centres 0..side-1 of the row come from one block, centre `side` from its +x neighbour.
        const int d = 2 * (j == side) + 4 * (k == side);
        const int block_j = j == side ? 0 : j, block_k = k == side ? 0 : k;
        VoxelClasses row;
        if (nb[d] != nullptr)
          row = classifyVoxels(&voxels[d][VoxelBlock::indexInLevel(side, 0, block_j, block_k)], side);
        else
          row.unobserved = row_bits;
        if (nb[d + 1] != nullptr)
          classifyVoxelsScalar(&voxels[d + 1][VoxelBlock::indexInLevel(side, 0, block_j, block_k)], 1, side, &row);
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
        unknown |= static_cast<uint16_t>(~(row_negative[k + dk][j + dj] | row_nonnegative[k + dk][j + dj]));
      }
    // Over pairs (i, i+1): a candidate has no unobserved centre, and both signs or a centre
    // too near 0 to classify.
    const uint16_t pair_neg = neg | (neg >> 1), pair_nonneg = nonneg | (nonneg >> 1);
    const uint16_t pair_unknown = unknown | (unknown >> 1);
    const uint16_t pair_unobserved = unobserved | (unobserved >> 1);
    return static_cast<uint16_t>(((pair_neg & pair_nonneg) | pair_unknown) & ~pair_unobserved);
  }

  /// samplePoint() for uniform neighbourhoods, reading the voxels by index. Every point a
  /// uniform box uses is, per axis, an owner centre (one voxel), the block face (the last
  /// centre below it and the first above) or the +neighbour's first centre; blockField()
  /// returns exactly that voxel's value for each touching block (at most +0 instead of −0,
  /// which `acc`, starting at +0, absorbs either way). The sums below are samplePoint()'s float
  /// operations in its order (z, y, x outer to inner), so the result is the same bits. Here
  /// every weight is w = 1/s and their sum n·w (n = 1, 2, 4, 8) is a power of two, so dividing
  /// by it equals multiplying by its exact reciprocal (both round the same real number once).
  bool sampleUniformPoint(const int q[3], PointSample* out) const {
    const int level = this->level[0];
    const int shift = level + 1, side = levelSide(level);
    const float w = uniform_weight;
    if (q[0] < kBlockUnits && q[1] < kBlockUnits && q[2] < kBlockUnits) {
      // An owner centre, the most common point: one voxel, the loop below unrolled.
      const Voxel& v = voxels[0][VoxelBlock::indexInLevel(side, (q[0] - step[0]) >> shift, (q[1] - step[0]) >> shift,
                                                          (q[2] - step[0]) >> shift)];
      if (!(v.weight > 0.0f)) return false;
      // (0 + w·sdf) / w, as a product with 1/w = s; w·c / w for a colour byte c is c exactly.
      out->sdf = (0.0f + w * v.sdf_m) * static_cast<float>(step[0]);
      out->rgb[0] = static_cast<float>(v.r);
      out->rgb[1] = static_cast<float>(v.g);
      out->rgb[2] = static_cast<float>(v.b);
      return true;
    }
    // The blocks touching q in increasing d (samplePoint()'s z, y, x order), and per axis the
    // voxel index in the offset-0 block (offset-1 blocks are read at index 0).
    int low_index[3];
    for (int a = 0; a < 3; ++a) low_index[a] = q[a] >= kBlockUnits ? side - 1 : (q[a] - step[0]) >> shift;
    const int offset_index[2][3] = {{low_index[0], low_index[1] * side, low_index[2] * side * side}, {0, 0, 0}};
    float weight_sum = 0.0f, acc = 0.0f, acc_rgb[3] = {0, 0, 0};
    for (unsigned blocks = incidentBlocks(q, q); blocks != 0; blocks &= blocks - 1) {
      const int d = __builtin_ctz(blocks);
      if (nb[d] == nullptr) return false;
      const Voxel& v = voxels[d][offset_index[d & 1][0] + offset_index[(d >> 1) & 1][1] + offset_index[d >> 2][2]];
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

  // Mixed neighbourhoods: per present block, bit masks over i of its own mesh level's row
  // (j, k), built on first use (rows_ready bit j + 8k); the same classes as the row masks of
  // uniform neighbourhoods.
  uint8_t mask_unobserved[8][kFinestSide][kFinestSide];   // [d][k][j]
  uint8_t mask_negative[8][kFinestSide][kFinestSide];     // [d][k][j], sdf < −1e-30
  uint8_t mask_nonnegative[8][kFinestSide][kFinestSide];  // [d][k][j], sdf ≥ 0
  uint64_t rows_ready[8] = {};

  void ensureMaskRow(int d, int j, int k) {
    const uint64_t row_bit = uint64_t{1} << (j + kFinestSide * k);
    if (rows_ready[d] & row_bit) return;
    rows_ready[d] |= row_bit;
    const int side = levelSide(level[d]);
    const Voxel* row = voxels[d] + VoxelBlock::indexInLevel(side, 0, j, k);
    const VoxelClasses classes = classifyVoxels(row, side);
    mask_unobserved[d][k][j] = static_cast<uint8_t>(classes.unobserved);
    mask_negative[d][k][j] = static_cast<uint8_t>(classes.negative);
    mask_nonnegative[d][k][j] = static_cast<uint8_t>(classes.nonnegative);
  }

  /// The blocks d (bit d) that points of the closed box [lo, hi] touch (incidentRange() per
  /// axis), in increasing d: samplePoint()'s z, y, x order.
  static unsigned incidentBlocks(const int lo[3], const int hi[3]) {
    unsigned blocks = 0xFFu;
    for (int a = 0; a < 3; ++a) {
      if (lo[a] > kBlockUnits) blocks &= kOffsetOne[a];   // only offset 1 on this axis
      if (hi[a] < kBlockUnits) blocks &= ~kOffsetOne[a];  // only offset 0
    }
    return blocks;
  }
  /// Bit d set where block d has offset 1 on axis a.
  static constexpr unsigned kOffsetOne[3] = {0xAAu, 0xCCu, 0xF0u};

  /// What the voxel masks tell about the 8 corner samples of box [lo, hi] together: some
  /// corner unobserved, all certainly negative, all certainly non-negative, or undecided.
  /// Exact set algebra, no sampling: a block touching the box is incident to a product set
  /// of corners, so the voxels it weighs at them are the product of the per-axis unions of
  /// SupportIndexTable's index sets at lo and hi.
  PointClass classifyBoxCorners(const int lo[3], const int hi[3]) {
    const SupportIndexTable& table = supportIndexTable();
    bool all_negative = true, all_nonnegative = true;
    for (unsigned blocks = incidentBlocks(lo, hi); blocks != 0; blocks &= blocks - 1) {
      const int d = __builtin_ctz(blocks), dx = d & 1, dy = (d >> 1) & 1, dz = d >> 2;
      if (nb[d] == nullptr) return kPointUnobserved;
      const auto& bits = table.bits[level[d]];
      const uint8_t is = bits[lo[0]][dx] | bits[hi[0]][dx];
      const uint8_t js = bits[lo[1]][dy] | bits[hi[1]][dy];
      const uint8_t ks = bits[lo[2]][dz] | bits[hi[2]][dz];
      for (unsigned kb = ks; kb != 0; kb &= kb - 1)
        for (unsigned jb = js; jb != 0; jb &= jb - 1) {
          const int j = __builtin_ctz(jb), k = __builtin_ctz(kb);
          ensureMaskRow(d, j, k);
          if (mask_unobserved[d][k][j] & is) return kPointUnobserved;
          all_negative &= (is & ~mask_negative[d][k][j]) == 0;
          all_nonnegative &= (is & ~mask_nonnegative[d][k][j]) == 0;
        }
    }
    return all_negative ? kPointNegative : (all_nonnegative ? kPointNonNegative : kPointUndecided);
  }

  /// True if the observed voxels that any point of the closed box [lo, hi] may weigh all
  /// share one sign (all < −1e-30, or all ≥ 0). Every sample meshBox() takes for the box —
  /// corners, hanging points, face-grid crossings — lies in the closed box and is a convex
  /// combination of such voxels, or unobserved; so the box yields nothing. This decides the
  /// boxes whose corners share one sign but which carry hanging points, without sampling.
  bool boxSupportHasOneSign(const int lo[3], const int hi[3]) {
    const SupportIndexTable& table = supportIndexTable();
    bool all_negative = true, all_nonnegative = true;
    for (unsigned blocks = incidentBlocks(lo, hi); blocks != 0; blocks &= blocks - 1) {
      const int d = __builtin_ctz(blocks), dx = d & 1, dy = (d >> 1) & 1, dz = d >> 2;
      if (nb[d] == nullptr) continue;  // every point weighing an absent block is unobserved
      const auto& range = table.range[level[d]];
      const uint8_t is = range[lo[0]][hi[0]][dx];
      const uint8_t js = range[lo[1]][hi[1]][dy];
      const uint8_t ks = range[lo[2]][hi[2]][dz];
      for (unsigned kb = ks; kb != 0; kb &= kb - 1)
        for (unsigned jb = js; jb != 0; jb &= jb - 1) {
          const int j = __builtin_ctz(jb), k = __builtin_ctz(kb);
          ensureMaskRow(d, j, k);
          const uint8_t observed = is & ~mask_unobserved[d][k][j];
          all_negative &= (observed & ~mask_negative[d][k][j]) == 0;
          all_nonnegative &= (observed & ~mask_nonnegative[d][k][j]) == 0;
          if (!all_negative && !all_nonnegative) return false;
        }
    }
    return true;
  }

  /// Builds the grid's coordinates from the present blocks' levels (call after nb/step).
  void buildSampleGrid() {
    for (int a = 0; a < 3; ++a) {
      uint64_t used = uint64_t{1} << kBlockUnits;  // bit q: coordinate q is in the grid
      for (int d = 0; d < 8; ++d)
        if (nb[d] != nullptr) used |= levelCentreBits(level[d]) << (((d >> a) & 1) * kBlockUnits);
      used &= (uint64_t{2} << kMaxBoxCoord) - 1;
      std::fill(std::begin(grid_index[a]), std::end(grid_index[a]), int8_t{-1});
      grid_dim[a] = 0;
      for (; used != 0; used &= used - 1) {
        const int q = __builtin_ctzll(used);
        grid_index[a][q] = static_cast<int8_t>(grid_dim[a]);
        grid_coords[a][grid_dim[a]++] = q;
      }
    }
    const size_t n = static_cast<size_t>(grid_dim[0]) * grid_dim[1] * grid_dim[2];
    scratch->sample_state.assign(n, kUnknown);
    if (scratch->samples.size() < n) scratch->samples.resize(n);
  }
};

BlockMesher::BlockMesher(const MeshingParams& params, MesherPaths paths) : params_(params), paths_(paths) {}

bool BlockMesher::samplePoint(const Context& ctx, int qx, int qy, int qz, PointSample* out) const {
  const int q[3] = {qx, qy, qz};
  int first[3], last[3];
  for (int a = 0; a < 3; ++a) incidentRange(q[a], &first[a], &last[a]);
  float weight_sum = 0.0f, acc = 0.0f, acc_rgb[3] = {0, 0, 0};
  // Fixed order (z, y, x outer to inner): every owner sums a shared point identically.
  for (int dz = first[2]; dz <= last[2]; ++dz)
    for (int dy = first[1]; dy <= last[1]; ++dy)
      for (int dx = first[0]; dx <= last[0]; ++dx) {
        const int d = dx + 2 * dy + 4 * dz;
        if (ctx.nb[d] == nullptr) return false;
        const int local[3] = {qx - kBlockUnits * dx, qy - kBlockUnits * dy, qz - kBlockUnits * dz};
        float sdf, rgb[3];
        if (!blockField(ctx.voxels[d], ctx.level[d], local, &sdf, rgb)) return false;
        const float w = 1.0f / static_cast<float>(ctx.step[d]);  // finer block, nearer centre
        weight_sum += w;
        acc += w * sdf;
        for (int k = 0; k < 3; ++k) acc_rgb[k] += w * rgb[k];
      }
  out->sdf = acc / weight_sum;
  for (int k = 0; k < 3; ++k) out->rgb[k] = acc_rgb[k] / weight_sum;
  return true;
}

void BlockMesher::collectHangingPoints(const Context& ctx, int axis, const int fixed[3], int u0,
                                       int u1, std::vector<int>* points) const {
  // Every lattice point, of any block touching this line, strictly inside (u0, u1), ascending.
  points->clear();
  for (uint64_t bits = ctx.hangingBits(axis, fixed, u0, u1); bits != 0; bits &= bits - 1)
    points->push_back(__builtin_ctzll(bits));
}

void BlockMesher::faceGridLines(const Context& ctx, int normal_axis, int line_axis, const int lo[3],
                                const int hi[3], std::vector<int>* lines) const {
  int fixed[3];
  faceInteriorLine(normal_axis, line_axis, lo, fixed);
  collectHangingPoints(ctx, line_axis, fixed, lo[line_axis], hi[line_axis], lines);
}

void BlockMesher::faceInteriorLine(int normal_axis, int line_axis, const int lo[3], int fixed[3]) {
  // Lines across a face lying on a block face are both touching blocks' centre planes: the
  // lattice points of a line through the face's interior, where only those two blocks touch.
  const int other = 3 - normal_axis - line_axis;
  fixed[0] = lo[0];
  fixed[1] = lo[1];
  fixed[2] = lo[2];
  fixed[normal_axis] = kBlockUnits;
  fixed[other] = lo[other] >= kBlockUnits ? kBlockUnits + kBlockUnits / 2 : kBlockUnits / 2;
}

uint32_t BlockMesher::vertexOnEdge(Context& ctx, const int p[3], const PointSample& sp,
                                   const int q[3], const PointSample& sq) const {
  // Canonical direction (lexicographic), so every owner computes identical bits.
  const bool swap = lexLess(q, p);
  const int* a = swap ? q : p;
  const int* b = swap ? p : q;
  const PointSample& sa = swap ? sq : sp;
  const PointSample& sb = swap ? sp : sq;
  const uint64_t key = (packPoint(a) << 18) | packPoint(b);
  bool inserted = false;
  const uint32_t vertex = ctx.vertex_of->findOrInsert(key, static_cast<uint32_t>(ctx.out->positions.size()), &inserted);
  if (inserted) appendVertex(ctx, a, sa, b, sb);
  return vertex;
}

void BlockMesher::appendVertex(Context& ctx, const int a[3], const PointSample& sa, const int b[3],
                               const PointSample& sb) {
  // Eq. 2.11–2.12: k = (α − s1)/(s2 − s1) with α = 0. Kept off the end points so distinct
  // edges never produce coincident vertices.
  const float t = std::clamp(sa.sdf / (sa.sdf - sb.sdf), 1e-3f, 1.0f - 1e-3f);
  Eigen::Vector3d pos;
  for (int k = 0; k < 3; ++k) {
    const double ga = static_cast<double>(ctx.origin[k] + a[k]);
    const double gb = static_cast<double>(ctx.origin[k] + b[k]);
    pos[k] = (ga + t * (gb - ga)) * ctx.unit;
  }
  ctx.out->positions.push_back(pos.cast<float>());
  std::array<uint8_t, 3> rgb;
  for (int k = 0; k < 3; ++k)
    rgb[k] = static_cast<uint8_t>(std::clamp(sa.rgb[k] + t * (sb.rgb[k] - sa.rgb[k]) + 0.5f, 0.0f, 255.0f));
  ctx.out->colors.push_back(rgb);
}

bool BlockMesher::cachedSample(Context& ctx, const int q[3], PointSample* out) const {
  const int gx = ctx.grid_index[0][q[0]], gy = ctx.grid_index[1][q[1]], gz = ctx.grid_index[2][q[2]];
  if ((gx | gy | gz) < 0) return samplePoint(ctx, q[0], q[1], q[2], out);  // not expected
  const size_t g = (static_cast<size_t>(gz) * ctx.grid_dim[1] + gy) * ctx.grid_dim[0] + gx;
  MeshScratch& m = *ctx.scratch;
  uint8_t& state = m.sample_state[g];
  if (state == kUnknown) {
    state = samplePoint(ctx, q[0], q[1], q[2], &m.samples[g]) ? kObserved : kUnobserved;
  }
  if (state != kObserved) return false;
  *out = m.samples[g];
  return true;
}

bool BlockMesher::boxHasNoSurface(Context& ctx, const int lo[3], const int hi[3]) const {
  // Every point a generic box uses (corners, hanging points, face grid crossings) is a grid
  // point inside the closed box: if all of those are observed and share one sign, the box
  // has no crossing. Conservative: an unobserved grid point means "cannot tell".
  bool negative = false, positive = false;
  for (int iz = ctx.grid_index[2][lo[2]]; iz <= ctx.grid_index[2][hi[2]]; ++iz)
    for (int iy = ctx.grid_index[1][lo[1]]; iy <= ctx.grid_index[1][hi[1]]; ++iy)
      for (int ix = ctx.grid_index[0][lo[0]]; ix <= ctx.grid_index[0][hi[0]]; ++ix) {
        const int q[3] = {ctx.grid_coords[0][ix], ctx.grid_coords[1][iy], ctx.grid_coords[2][iz]};
        PointSample sample;
        if (!cachedSample(ctx, q, &sample)) return false;
        (sample.sdf >= 0.0f ? positive : negative) = true;
        if (positive && negative) return false;
      }
  return true;
}

bool BlockMesher::boxIsPlain(const Context& ctx, const int lo[3], const int hi[3]) const {
  // Plain boxes (8 corners, nothing on their edges or faces) use the case table. Only a box
  // touching a block face can carry extra points, and only when levels differ.
  if (ctx.uniform || !(hi[0] == kBlockUnits || hi[1] == kBlockUnits || hi[2] == kBlockUnits ||
                       lo[0] == kBlockUnits || lo[1] == kBlockUnits || lo[2] == kBlockUnits))
    return true;
  for (int axis = 0; axis < 3; ++axis)
    for (int c = 0; c < 4; ++c) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      int fixed[3];
      fixed[a] = (c & 1) ? hi[a] : lo[a];
      fixed[b] = (c & 2) ? hi[b] : lo[b];
      fixed[axis] = lo[axis];
      if (ctx.hangingBits(axis, fixed, lo[axis], hi[axis]) != 0) return false;
    }
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      if ((side ? hi[axis] : lo[axis]) != kBlockUnits) continue;
      for (int k = 1; k < 3; ++k) {
        const int line_axis = (axis + k) % 3;
        int fixed[3];
        faceInteriorLine(axis, line_axis, lo, fixed);
        if (ctx.hangingBits(line_axis, fixed, lo[line_axis], hi[line_axis]) != 0) return false;
      }
    }
  return true;
}

void BlockMesher::meshBox(Context& ctx, const int lo[3], const int hi[3]) const {
  // The 8 corners first: both the plain and the generic path give up on a box with an
  // unobserved corner, and most boxes have no sign change at all.
  int corner[8][3];
  PointSample s[8];
  int case_index = 0;
  for (int c = 0; c < 8; ++c) {
    corner[c][0] = (c & 1) ? hi[0] : lo[0];
    corner[c][1] = (c & 2) ? hi[1] : lo[1];
    corner[c][2] = (c & 4) ? hi[2] : lo[2];
    if (!cachedSample(ctx, corner[c], &s[c])) return;
    case_index |= (s[c].sdf >= 0.0f) << c;
  }
  const bool single_sign = case_index == 0 || case_index == 255;
  if (boxIsPlain(ctx, lo, hi)) {
    if (!single_sign) meshPlainBox(ctx, corner, s);
    return;
  }
  // Hanging points may change sign even when the corners do not.
  if (single_sign && boxHasNoSurface(ctx, lo, hi)) return;
  meshGenericBox(ctx, lo, hi);
}

void BlockMesher::meshUniformBox(Context& ctx, const int lo[3], const int hi[3], const int grid_lo[3]) const {
  // meshBox() + meshPlainBox() for a uniform neighbourhood (every box plain): corners by cache
  // slot, only the crossing edges tested for the truncation band, edges → vertices by slot.
  MeshScratch& m = *ctx.scratch;
  const size_t base = grid_lo[0] + ctx.grid_dim[0] * (grid_lo[1] + static_cast<size_t>(ctx.grid_dim[1]) * grid_lo[2]);
  size_t slot[8];
  int case_index = 0;
  for (int c = 0; c < 8; ++c) {
    const size_t g = base + ctx.uniform_corner_offset[c];
    uint8_t& state = m.sample_state[g];
    if (state == kUnknown) {
      const int q[3] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]};
      state = ctx.sampleUniformPoint(q, &m.samples[g]) ? kObserved : kUnobserved;
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
  // First use of an edge comes first, as in meshPlainBox(): vertices are numbered alike.
  for (const auto& tri : mc::caseTable().triangles[case_index]) {
    std::array<uint32_t, 3> t;
    for (int v = 0; v < 3; ++v) {
      const mc::CubeEdge& e = edges[tri[v]];
      const int axis = __builtin_ctz(static_cast<unsigned>(e.corner_a ^ e.corner_b));
      MeshScratch::EdgeVertex& entry = m.uniform_edge_vertex[3 * slot[e.corner_a] + axis];
      if (entry.stamp != m.uniform_edge_stamp) {
        // corner_a is the low end on `axis`: the canonical direction vertexOnEdge() uses.
        const int a[3] = {(e.corner_a & 1) ? hi[0] : lo[0], (e.corner_a & 2) ? hi[1] : lo[1], (e.corner_a & 4) ? hi[2] : lo[2]};
        const int b[3] = {(e.corner_b & 1) ? hi[0] : lo[0], (e.corner_b & 2) ? hi[1] : lo[1], (e.corner_b & 4) ? hi[2] : lo[2]};
        entry = {m.uniform_edge_stamp, static_cast<uint32_t>(ctx.out->positions.size())};
        appendVertex(ctx, a, m.samples[slot[e.corner_a]], b, m.samples[slot[e.corner_b]]);
      }
      t[v] = entry.vertex;
    }
    ctx.out->triangles.push_back(t);
  }
}

void BlockMesher::meshPlainBox(Context& ctx, const int corner[8][3], const PointSample s[8]) const {
  int case_index = 0;
  for (int c = 0; c < 8; ++c) case_index |= (s[c].sdf >= 0.0f) << c;
  const auto& edges = mc::cubeEdges();
  for (const mc::CubeEdge& e : edges) {
    const float va = s[e.corner_a].sdf, vb = s[e.corner_b].sdf;
    if ((va >= 0.0f) != (vb >= 0.0f) && std::min(std::abs(va), std::abs(vb)) >= ctx.truncated_abs)
      return;  // truncation-band edge, not a surface
  }
  // Most crossing edges serve two triangles of the box: look each up once. (The first use of
  // an edge still comes first, so vertices are numbered as before.)
  constexpr uint32_t kNoVertex = ~uint32_t{0};
  uint32_t edge_vertex[12];
  std::fill(std::begin(edge_vertex), std::end(edge_vertex), kNoVertex);
  for (const auto& tri : mc::caseTable().triangles[case_index]) {
    std::array<uint32_t, 3> t;
    for (int v = 0; v < 3; ++v) {
      uint32_t& vertex = edge_vertex[tri[v]];
      if (vertex == kNoVertex) {
        const mc::CubeEdge& e = edges[tri[v]];
        vertex = vertexOnEdge(ctx, corner[e.corner_a], s[e.corner_a], corner[e.corner_b], s[e.corner_b]);
      }
      t[v] = vertex;
    }
    ctx.out->triangles.push_back(t);
  }
}

void BlockMesher::meshGenericBox(Context& ctx, const int lo[3], const int hi[3]) const {
  // Generic box: tile each face, put every lattice point on an edge into the polygons.
  MeshScratch& m = *ctx.scratch;
  std::vector<std::array<int, 3>>& points = m.points;
  points.clear();
  auto pointId = [&](const int q[3]) {
    // Few points per box (corners + hanging points): a linear search beats hashing.
    for (size_t i = 0; i < points.size(); ++i)
      if (points[i][0] == q[0] && points[i][1] == q[1] && points[i][2] == q[2]) return static_cast<int>(i);
    points.push_back({q[0], q[1], q[2]});
    return static_cast<int>(points.size() - 1);
  };
  size_t polygon_count = 0;
  for (auto& poly : m.polygons) poly.clear();  // unused trailing polygons stay empty
  std::vector<int>& grid_u = m.grid_u;
  std::vector<int>& grid_v = m.grid_v;
  std::vector<int>& hanging = m.hanging;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      const int plane = side ? hi[axis] : lo[axis];
      grid_u.assign(1, lo[u]);
      grid_v.assign(1, lo[v]);
      if (plane == kBlockUnits) {
        faceGridLines(ctx, axis, u, lo, hi, &m.lines);
        grid_u.insert(grid_u.end(), m.lines.begin(), m.lines.end());
        faceGridLines(ctx, axis, v, lo, hi, &m.lines);
        grid_v.insert(grid_v.end(), m.lines.begin(), m.lines.end());
      }
      grid_u.push_back(hi[u]);
      grid_v.push_back(hi[v]);
      for (size_t iu = 0; iu + 1 < grid_u.size(); ++iu)
        for (size_t iv = 0; iv + 1 < grid_v.size(); ++iv) {
          // Tile corners counter-clockwise seen from outside (e_u × e_v = e_axis).
          int cu[4] = {grid_u[iu], grid_u[iu + 1], grid_u[iu + 1], grid_u[iu]};
          int cv[4] = {grid_v[iv], grid_v[iv], grid_v[iv + 1], grid_v[iv + 1]};
          if (side == 0) {
            std::swap(cu[1], cu[3]);
            std::swap(cv[1], cv[3]);
          }
          if (polygon_count == m.polygons.size()) m.polygons.emplace_back();
          std::vector<int>& poly = m.polygons[polygon_count++];
          for (int c = 0; c < 4; ++c) {
            int p[3];
            p[axis] = plane;
            p[u] = cu[c];
            p[v] = cv[c];
            poly.push_back(pointId(p));
            // Points on the tile edge towards the next corner, in walking order.
            const int n = (c + 1) % 4;
            const int edge_axis = cu[c] != cu[n] ? u : v;
            const int from = edge_axis == u ? cu[c] : cv[c];
            const int to = edge_axis == u ? cu[n] : cv[n];
            collectHangingPoints(ctx, edge_axis, p, std::min(from, to), std::max(from, to), &hanging);
            if (from > to) std::reverse(hanging.begin(), hanging.end());
            for (int h : hanging) {
              int hp[3] = {p[0], p[1], p[2]};
              hp[edge_axis] = h;
              poly.push_back(pointId(hp));
            }
          }
        }
    }
  }
  std::vector<PointSample>& samples = *ctx.vertex_samples;
  samples.resize(points.size());
  m.values.resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    if (!cachedSample(ctx, points[i].data(), &samples[i])) return;
    m.values[i] = samples[i].sdf;
  }
  const float* values = m.values.data();
  m.triangles.clear();
  mc::polygonizeCell(m.polygons, values, &m.triangles);  // empty trailing polygons add nothing
  for (const auto& tri : m.triangles)
    for (const mc::Crossing& c : tri)
      if (std::min(std::abs(values[c.a]), std::abs(values[c.b])) >= ctx.truncated_abs) return;
  for (const auto& tri : m.triangles) {
    std::array<uint32_t, 3> t;
    for (int k = 0; k < 3; ++k)
      t[k] = vertexOnEdge(ctx, points[tri[k].a].data(), samples[tri[k].a], points[tri[k].b].data(),
                          samples[tri[k].b]);
    ctx.out->triangles.push_back(t);
  }
}

void BlockMesher::mesh(const BlockOctree& map, const MeshStates& states, const VoxelBlock& owner,
                       SubMesh* out, const SeamFills* seam_fills) const {
  out->clear();
  out->key = owner.key;
  const int owner_level = states[owner].level;
  out->level = owner_level;
  thread_local MeshScratch scratch;
  thread_local std::vector<PointSample> vertex_samples;
  Context ctx;
  ctx.out = out;
  ctx.scratch = &scratch;
  scratch.vertex_of.clear();
  ctx.vertex_of = &scratch.vertex_of;
  ctx.vertex_samples = &vertex_samples;
  ctx.unit = params_.voxel_size_m / 2.0;
  ctx.origin[0] = int64_t{owner.key.x} * kBlockUnits;
  ctx.origin[1] = int64_t{owner.key.y} * kBlockUnits;
  ctx.origin[2] = int64_t{owner.key.z} * kBlockUnits;
  bool any_negative = false, any_positive = false;
  int coarsest_level = 0;
  for (int d = 0; d < 8; ++d) {
    ctx.nb[d] = map.neighbour(owner, d & 1, (d >> 1) & 1, (d >> 2) & 1);
    ctx.level[d] = ctx.nb[d] ? states[*ctx.nb[d]].level : 0;
    if (ctx.nb[d] != nullptr) {
      const bool prepared = seam_fills != nullptr && ctx.nb[d]->row < seam_fills->size() &&
                            !(*seam_fills)[*ctx.nb[d]].empty();
      ctx.voxels[d] = prepared ? (*seam_fills)[*ctx.nb[d]].data()
                               : meshVoxels(*ctx.nb[d], states[*ctx.nb[d]], &scratch.seam_fills[d]);
    }
    ctx.step[d] = 1 << ctx.level[d];
    if (ctx.nb[d] == nullptr) continue;
    coarsest_level = std::max(coarsest_level, ctx.level[d]);
    // Of the +neighbour d the owner reads only what lies near its faces towards the owner.
    any_negative |= (states[*ctx.nb[d]].sign_bits & meshSignBit(d, false)) != 0;
    any_positive |= (states[*ctx.nb[d]].sign_bits & meshSignBit(d, true)) != 0;
  }
  ctx.truncated_abs = static_cast<float>(0.99 * TruncationBand(params_.voxel_size_m, params_.truncation_vox)
                                                     .measurementM(coarsest_level));
  // Once the neighbourhood is final: whether it is uniform, and the owner's sample grid.
  auto prepareBoxes = [&] {
    for (int d = 1; d < 8; ++d)
      if (ctx.nb[d] && ctx.level[d] != owner_level) ctx.uniform = false;
    ctx.buildSampleGrid();
  };
  // The one place the paths part. Both give the same bits (test_block_mesher_fast_paths).
  switch (paths_) {
    case MesherPaths::kGeneralOnly:
      prepareBoxes();
      meshEveryBox(ctx);
      break;
    case MesherPaths::kFast:
      // Every value the mesher uses is a convex combination of observed voxels in these
      // regions: with one sign only, no cell can change sign.
      if (!any_negative || !any_positive) return;
      // A +neighbour with nothing observed where the owner reads it adds only points that are
      // unobserved, present or not: every box with such a point — its own boxes, and any box
      // whose edges or faces it would tile with hanging points (their corners on the shared
      // line weigh it) — gives up either way. Meshing as if it were absent gives the same
      // bits, and a neighbourhood that differed only by it takes the uniform path.
      // (truncated_abs above still counts it: that is what the general path uses.)
      for (int d = 1; d < 8; ++d)
        if (ctx.nb[d] && (states[*ctx.nb[d]].sign_bits & (meshSignBit(d, false) | meshSignBit(d, true))) == 0)
          ctx.nb[d] = nullptr;
      prepareBoxes();
      if (ctx.uniform)
        meshUniformBoxes(ctx);
      else
        meshMixedBoxes(ctx);
      break;
  }
  computeVertexNormals(out);
}

void BlockMesher::meshEveryBox(Context& ctx) const {
  ctx.buildLinePoints();
  std::pair<int, int> intervals[3][kFinestSide];
  int interval_count[3];
  for (int d = 0; d < 8; ++d) {
    if (ctx.nb[d] == nullptr) continue;
    const int step = ctx.step[d];
    const int side = kFinestSide / step;
    for (int a = 0; a < 3; ++a) {
      int& n = interval_count[a];
      n = 0;
      if ((d >> a) & 1) {
        intervals[a][n++] = {kBlockUnits, kBlockUnits + step};  // neighbour's low skin
      } else {
        for (int i = 0; i + 1 < side; ++i) intervals[a][n++] = {step * (2 * i + 1), step * (2 * i + 3)};
        intervals[a][n++] = {step * (2 * side - 1), kBlockUnits};  // own high skin
      }
    }
    for (int iz = 0; iz < interval_count[2]; ++iz)
      for (int iy = 0; iy < interval_count[1]; ++iy)
        for (int ix = 0; ix < interval_count[0]; ++ix) {
          const int lo[3] = {intervals[0][ix].first, intervals[1][iy].first, intervals[2][iz].first};
          const int hi[3] = {intervals[0][ix].second, intervals[1][iy].second, intervals[2][iz].second};
          const bool core = d == 0 && hi[0] < kBlockUnits && hi[1] < kBlockUnits && hi[2] < kBlockUnits;
          // Most boxes: no voxel-level sign change, decided exactly on the corner voxels.
          if (core && ctx.coreBoxIsEmpty(lo)) continue;
          meshBox(ctx, lo, hi);
        }
  }
}

void BlockMesher::meshUniformBoxes(Context& ctx) const {
  ctx.buildRowMasks();
  ctx.uniform_weight = 1.0f / static_cast<float>(ctx.step[0]);
  const size_t stride_y = ctx.grid_dim[0], stride_z = stride_y * ctx.grid_dim[1];
  for (int c = 0; c < 8; ++c)
    ctx.uniform_corner_offset[c] = (c & 1) + ((c >> 1) & 1) * stride_y + (c >> 2) * stride_z;
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
    for (int j = 0; j < side; ++j) candidates[k][j] = ctx.candidateStarts(j, k);
  // Same box order as meshMixedBoxes(): by block d, then z, y, x — the submesh's vertex and
  // triangle order does not depend on which path ran.
  for (int d = 0; d < 8; ++d) {
    if (ctx.nb[d] == nullptr) continue;
    int first[3], last[3];
    for (int a = 0; a < 3; ++a) {
      first[a] = (d >> a) & 1 ? side - 1 : 0;
      last[a] = side - 1;
    }
    const uint16_t x_range = static_cast<uint16_t>(((1u << (last[0] + 1)) - 1) & ~((1u << first[0]) - 1));
    for (int k = first[2]; k <= last[2]; ++k)
      for (int j = first[1]; j <= last[1]; ++j)
        for (uint16_t bits = candidates[k][j] & x_range; bits != 0; bits &= bits - 1) {
          const int i = __builtin_ctz(bits);
          int lo[3], hi[3], grid_lo[3];
          interval(i, d & 1, &lo[0], &hi[0], &grid_lo[0]);
          interval(j, (d >> 1) & 1, &lo[1], &hi[1], &grid_lo[1]);
          interval(k, (d >> 2) & 1, &lo[2], &hi[2], &grid_lo[2]);
          meshUniformBox(ctx, lo, hi, grid_lo);
        }
  }
}

void BlockMesher::meshMixedBoxes(Context& ctx) const {
  ctx.buildLinePoints();

  // Box extents per axis: at most kFinestSide intervals (fixed arrays: no allocation).
  std::pair<int, int> intervals[3][kFinestSide];
  int interval_count[3];
  for (int d = 0; d < 8; ++d) {
    if (ctx.nb[d] == nullptr) continue;
    const int step = ctx.step[d];
    const int side = kFinestSide / step;
    for (int a = 0; a < 3; ++a) {
      int& n = interval_count[a];
      n = 0;
      if ((d >> a) & 1) {
        intervals[a][n++] = {kBlockUnits, kBlockUnits + step};  // neighbour's low skin
      } else {
        for (int i = 0; i + 1 < side; ++i) intervals[a][n++] = {step * (2 * i + 1), step * (2 * i + 3)};
        intervals[a][n++] = {step * (2 * side - 1), kBlockUnits};  // own high skin
      }
    }
    auto visit = [&](int ix, int iy, int iz) {
      const int lo[3] = {intervals[0][ix].first, intervals[1][iy].first, intervals[2][iz].first};
      const int hi[3] = {intervals[0][ix].second, intervals[1][iy].second, intervals[2][iz].second};
      const bool core = d == 0 && hi[0] < kBlockUnits && hi[1] < kBlockUnits && hi[2] < kBlockUnits;
      if (core) {
        // Most boxes: no voxel-level sign change. The exact corner signs decide here, so
        // the mask pre-test below could not reject a box that passes.
        if (ctx.coreBoxIsEmpty(lo)) return;
      } else if (mixedBoxIsEmpty(ctx, lo, hi)) {
        return;
      }
      meshBox(ctx, lo, hi);
    };
    for (int iz = 0; iz < interval_count[2]; ++iz)
      for (int iy = 0; iy < interval_count[1]; ++iy) {
        if (d == 0 && iy + 1 < interval_count[1] && iz + 1 < interval_count[2]) {
          // A row of core boxes and the skin box ending it: only the core boxes whose corners'
          // voxel masks allow a surface (coreCandidates()), in the same x order.
          for (unsigned bits = ctx.coreCandidates(iy, iz); bits != 0; bits &= bits - 1) visit(__builtin_ctz(bits), iy, iz);
          visit(interval_count[0] - 1, iy, iz);
          continue;
        }
        for (int ix = 0; ix < interval_count[0]; ++ix) visit(ix, iy, iz);
      }
  }
}

bool BlockMesher::mixedBoxIsEmpty(Context& ctx, const int lo[3], const int hi[3]) const {
  // meshBox() returns without output at an unobserved corner, and on a plain box whose corners
  // share one sign; both are read off the voxel masks here without summing any sample. A box
  // with hanging points can change sign between its corners, unless every voxel its points
  // may weigh has the corners' sign (boxSupportHasOneSign()); otherwise meshBox() decides.
  switch (ctx.classifyBoxCorners(lo, hi)) {
    case kPointUnobserved: return true;
    case kPointNegative:
    case kPointNonNegative: return boxIsPlain(ctx, lo, hi) || ctx.boxSupportHasOneSign(lo, hi);
    default: return false;
  }
}

void computeVertexNormals(TriangleMesh* mesh) {
  mesh->normals.assign(mesh->positions.size(), Eigen::Vector3f::Zero());
  for (const auto& t : mesh->triangles) {
    const Eigen::Vector3f n = (mesh->positions[t[1]] - mesh->positions[t[0]])
                                  .cross(mesh->positions[t[2]] - mesh->positions[t[0]]);
    for (uint32_t v : t) mesh->normals[v] += n;
  }
  for (Eigen::Vector3f& n : mesh->normals) {
    const float len = n.norm();
    n = len > 0.0f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::UnitZ();
  }
}

}  // namespace stereo_fusion
