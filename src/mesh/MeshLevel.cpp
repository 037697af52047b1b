// The per-block mesh level and sign bits (declared in BlockMesher.h). They run on the fusion
// workers for every updated block, apart from the mesher itself.

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "stereo_fusion/mesh/BlockMesher.h"
#include "stereo_fusion/util/CpuFeatures.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define STEREO_FUSION_HAVE_AVX2_REFRESH 1
#endif

namespace stereo_fusion {
namespace {

/// chooseMeshLevel()'s decision from the number of observed voxels of each level.
int levelFromObservedCounts(const int observed[kNumLevels], double level_min_coverage) {
  // Observed surface area of each level, in finest-voxel units: a level's band is
  // truncation_vox of its own voxels thick, so area ≈ observed volume / thickness ∝ n · s².
  // Areas, not voxel shares: a coarse centre can miss the band that finer centres near the
  // block's faces catch, so no level is assumed to contain another.
  double area[kNumLevels];
  double largest = 0.0;
  for (int level = 0; level < kNumLevels; ++level) {
    const double scale = levelScale(level);
    area[level] = observed[level] * scale * scale;
    largest = std::max(largest, area[level]);
  }
  for (int level = 0; level < kNumLevels; ++level)
    if (largest > 0.0 && area[level] >= level_min_coverage * largest) return level;
  return kNumLevels - 1;
}

}  // namespace

namespace {

/// The trilinear field of `voxels` (one level of `side`³ voxels) at `position`, given in that
/// level's voxel units (voxel centres at whole numbers), extrapolated linearly beyond its outer
/// centres. False if a voxel it weighs is unobserved.
bool linearField(const Voxel* voxels, int side, const float position[3], float* sdf, float rgb[3]) {
  int i0[3];
  float frac[3];
  for (int a = 0; a < 3; ++a) {
    i0[a] = std::clamp(static_cast<int>(std::floor(position[a])), 0, side - 2);
    frac[a] = position[a] - static_cast<float>(i0[a]);
  }
  return trilinearVoxels(voxels, side, i0, frac, sdf, rgb);
}

}  // namespace

bool fillFacesFromCoarserLevels(const VoxelBlock& block, int level, std::vector<Voxel>* out) {
  out->clear();
  const int side = levelSide(level);
  const Voxel* voxels = block.level(level);
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j) {
      const bool on_face_jk = j == 0 || k == 0 || j == side - 1 || k == side - 1;
      // Off the y/z faces only i = 0 and i = side − 1 lie on a face.
      for (int i = 0; i < side; i += on_face_jk ? 1 : side - 1) {
        const int index = VoxelBlock::indexInLevel(side, i, j, k);
        if (voxels[index].weight > 0.0f) continue;
        for (int coarser = level + 1; coarser < kNumLevels; ++coarser) {
          if (!block.hasLevel(coarser)) continue;
          // Centre (i + ½)·s_level in finest voxels; in coarser voxel units, centres at whole
          // numbers.
          const float ratio =
              static_cast<float>(levelScale(level)) / static_cast<float>(levelScale(coarser));
          const float position[3] = {(i + 0.5f) * ratio - 0.5f, (j + 0.5f) * ratio - 0.5f,
                                     (k + 0.5f) * ratio - 0.5f};
          float sdf, rgb[3];
          if (!linearField(block.level(coarser), levelSide(coarser), position, &sdf, rgb)) continue;
          if (out->empty()) out->assign(voxels, voxels + levelVoxelCount(level));
          Voxel& v = (*out)[index];
          v.sdf_m = sdf;
          v.weight = 1.0f;
          v.r = static_cast<uint8_t>(std::lround(std::clamp(rgb[0], 0.0f, 255.0f)));
          v.g = static_cast<uint8_t>(std::lround(std::clamp(rgb[1], 0.0f, 255.0f)));
          v.b = static_cast<uint8_t>(std::lround(std::clamp(rgb[2], 0.0f, 255.0f)));
          break;
        }
        if (side == 1) break;
      }
    }
  return !out->empty();
}

const Voxel* meshVoxels(const VoxelBlock& block, const MeshBlockState& state,
                        std::vector<Voxel>* scratch) {
  if (!state.seam_filled) return block.level(state.level);
  fillFacesFromCoarserLevels(block, state.level, scratch);
  return scratch->data();
}

int chooseMeshLevel(const VoxelBlock& block, double level_min_coverage) {
  int observed[kNumLevels] = {};
  for (int level = 0; level < kNumLevels; ++level) {
    if (!block.hasLevel(level)) continue;  // never updated: nothing observed
    const Voxel* voxels = block.level(level);
    for (int n = 0; n < levelVoxelCount(level); ++n) observed[level] += voxels[n].weight > 0.0f;
  }
  return levelFromObservedCounts(observed, level_min_coverage);
}

namespace {
/// refreshMeshSigns() over `voxels`, the block's meshed voxels at `level`.
uint16_t meshSignBits(const Voxel* voxels, int level) {
  const int side = levelSide(level), step = levelScale(level);
  // The owners below reach at most 4 half-voxel units into this block (the coarsest level's
  // first centre), where blockField() weighs up to the next centre beyond: every voxel they
  // can read has its centre below 8 units, i.e. within 4 finest voxels of the face.
  auto near_low_face = [step](int i) { return step * (2 * i + 1) < 8 ? 1 : 0; };
  uint16_t seen[8] = {};  // by the axes a voxel is near the low face on: its signs (region-0 bits)
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) {
        const Voxel& v = voxels[VoxelBlock::indexInLevel(side, i, j, k)];
        if (!(v.weight > 0.0f)) continue;
        // A value in [−1e-30, 0) counts as both signs: the mesher's weighted sums can round it
        // to −0, which compares as non-negative.
        const uint16_t sign =
            v.sdf_m >= 0.0f ? meshSignBit(0, true)
            : v.sdf_m < -1e-30f
                ? meshSignBit(0, false)
                : static_cast<uint16_t>(meshSignBit(0, false) | meshSignBit(0, true));
        seen[near_low_face(i) | 2 * near_low_face(j) | 4 * near_low_face(k)] |= sign;
      }
  // Region r holds the voxels near the low face on every axis of r.
  uint16_t bits = 0;
  for (int region = 0; region < 8; ++region)
    for (int near = 0; near < 8; ++near)
      if ((region & near) == region) bits |= static_cast<uint16_t>(seen[near] << (2 * region));
  return bits;
}

/// The fill scratch of the refresh on this thread.
std::vector<Voxel>& refreshScratch() {
  thread_local std::vector<Voxel> scratch;
  return scratch;
}
}  // namespace

void refreshMeshSigns(const VoxelBlock& block, MeshBlockState* state) {
  state->sign_bits = meshSignBits(meshVoxels(block, *state, &refreshScratch()), state->level);
}

void refreshMeshLevel(const VoxelBlock& block, const MeshingParams& params, MeshBlockState* state,
                      std::vector<Voxel>* fill) {
  static const bool use_avx2 = avx2Supported();
  if (use_avx2)
    refreshMeshLevelAvx2(block, params, state, fill);
  else
    refreshMeshLevelScalar(block, params, state, fill);
}

namespace {
/// Sets state->seam_filled for state->level; returns the voxels to take the signs of.
const Voxel* refreshSeamFill(const VoxelBlock& block, const MeshingParams& params,
                             MeshBlockState* state, std::vector<Voxel>* fill) {
  std::vector<Voxel>& out = fill != nullptr ? *fill : refreshScratch();
  out.clear();
  state->seam_filled = params.fill_faces_from_coarser_levels &&
                       fillFacesFromCoarserLevels(block, state->level, &out);
  return state->seam_filled ? out.data() : block.level(state->level);
}
}  // namespace

void refreshMeshLevelScalar(const VoxelBlock& block, const MeshingParams& params,
                            MeshBlockState* state, std::vector<Voxel>* fill) {
  state->level = static_cast<int8_t>(chooseMeshLevel(block, params.level_min_coverage));
  state->sign_bits = meshSignBits(refreshSeamFill(block, params, state, fill), state->level);
}

#ifdef STEREO_FUSION_HAVE_AVX2_REFRESH
// ---------------------------------------------------------------------------------------------
// AVX2 path: eight consecutive voxels of a level per step (levels start at multiples of 8).

namespace {

#define SF_AVX2 __attribute__((target("avx2"), always_inline)) inline

/// The 96 bytes of eight voxels as three vectors of {sdf, weight, rgb} dword triples.
struct EightVoxels {
  __m256 v0, v1, v2;
};

SF_AVX2 EightVoxels loadEight(const Voxel* voxels) {
  static_assert(sizeof(Voxel) == 12 && offsetof(Voxel, weight) == 4,
                "voxels are {sdf, weight, rgb} dword triples");
  const float* dwords = reinterpret_cast<const float*>(voxels);
  return {_mm256_loadu_ps(dwords), _mm256_loadu_ps(dwords + 8), _mm256_loadu_ps(dwords + 16)};
}

// Dword 3n + q is field q of voxel n, in vector (3n + q) / 8 at lane (3n + q) mod 8: two blends
// collect one field of all eight voxels (voxel n in lane 3n + q mod 8), a permutation puts
// voxel n into lane n (as the fusion kernel's loadVoxels()).
SF_AVX2 __m256 sdfLanes(const EightVoxels& e) {
  return _mm256_permutevar8x32_ps(
      _mm256_blend_ps(_mm256_blend_ps(e.v0, e.v1, 0b10010010), e.v2, 0b00100100),
      _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
}
/// The weights, voxel n in lane 3n + 1 mod 8: enough for counting.
SF_AVX2 __m256 weightsUnordered(const EightVoxels& e) {
  return _mm256_blend_ps(_mm256_blend_ps(e.v0, e.v1, 0b00100100), e.v2, 0b01001001);
}
SF_AVX2 __m256 weightLanes(const EightVoxels& e) {
  return _mm256_permutevar8x32_ps(weightsUnordered(e), _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6));
}

/// −1 in the lanes of eight voxels (in some order) that are observed (weight > 0), else 0.
SF_AVX2 __m256i observedLanes(const Voxel* voxels) {
  return _mm256_castps_si256(
      _mm256_cmp_ps(weightsUnordered(loadEight(voxels)), _mm256_setzero_ps(), _CMP_GT_OQ));
}

/// Observed voxels (weight > 0) of `kLevel`, whose voxels start at `voxels`.
template <int kLevel>
SF_AVX2 int countObservedAvx2(const Voxel* voxels) {
  // Subtracting the −1 masks counts per lane; one horizontal sum at the end.
  __m256i counts = _mm256_setzero_si256();
  int n = 0;
  // Sixteen voxels per step: half the loop overhead, and GCC's extra register copy per step.
  for (; n + 16 <= levelVoxelCount(kLevel); n += 16)
    counts = _mm256_sub_epi32(
        counts, _mm256_add_epi32(observedLanes(voxels + n), observedLanes(voxels + n + 8)));
  if (n < levelVoxelCount(kLevel)) counts = _mm256_sub_epi32(counts, observedLanes(voxels + n));
  __m128i sum = _mm_add_epi32(_mm256_castsi256_si128(counts), _mm256_extracti128_si256(counts, 1));
  sum = _mm_add_epi32(sum, _mm_shuffle_epi32(sum, 0x4E));
  sum = _mm_add_epi32(sum, _mm_shuffle_epi32(sum, 0xB1));
  return _mm_cvtsi128_si32(sum);
}

/// Bit n: voxel n of the eight is observed and holds a value refreshMeshSigns() counts as
/// < 0 (`negative`) or as ≥ 0 (`non_negative`); [−1e-30, 0) and NaN are in both.
struct SignLanes {
  unsigned negative, non_negative;
};

SF_AVX2 SignLanes signLanesAvx2(const Voxel* voxels) {
  const EightVoxels e = loadEight(voxels);
  const __m256 sdf = sdfLanes(e);
  const unsigned observed = static_cast<unsigned>(
      _mm256_movemask_ps(_mm256_cmp_ps(weightLanes(e), _mm256_setzero_ps(), _CMP_GT_OQ)));
  // !(sdf ≥ 0) and !(sdf < −1e-30): the complements of the scalar tests, NaN included.
  const unsigned negative = static_cast<unsigned>(
      _mm256_movemask_ps(_mm256_cmp_ps(sdf, _mm256_setzero_ps(), _CMP_NGE_UQ)));
  const unsigned non_negative = static_cast<unsigned>(
      _mm256_movemask_ps(_mm256_cmp_ps(sdf, _mm256_set1_ps(-1e-30f), _CMP_NLT_UQ)));
  return {negative & observed, non_negative & observed};
}

// Which voxels of a group of eight lie in the low half of the block on each axis (what
// refreshMeshSigns() calls near the low face): on x by lane alone; on y and z by group, except
// in level 2, whose single group holds both halves. Level 0: group j + 8k, lane i. Level 1:
// group 2k + h, lane i + 4(j − 2h). Level 2: lane i + 2j + 4k.
constexpr unsigned kLowHalfLanes[kNumLevels][3] = {
    {0x0F, 0xFF, 0xFF}, {0x33, 0xFF, 0xFF}, {0x55, 0x33, 0x0F}};
constexpr bool groupInLowHalf(int level, int group, int axis) {
  if (level == 0) return (axis == 1 ? group % 8 : group / 8) < 4;
  if (level == 1) return axis == 1 ? group % 2 == 0 : group / 2 < 2;
  return true;
}

/// The tables above against the voxel indices (eq. 3.4): voxel n of group g is index 8g + n.
constexpr bool lowHalfTablesMatchIndices() {
  for (int level = 0; level < kNumLevels; ++level) {
    const int side = levelSide(level);
    for (int index = 0; index < levelVoxelCount(level); ++index) {
      const int ijk[3] = {index % side, index / side % side, index / (side * side)};
      for (int axis = 0; axis < 3; ++axis) {
        const bool lane_low = (kLowHalfLanes[level][axis] >> (index % 8)) & 1;
        const bool group_low = axis == 0 || groupInLowHalf(level, index / 8, axis);
        if ((ijk[axis] < side / 2) != (lane_low && group_low)) return false;
      }
    }
  }
  return true;
}
static_assert(lowHalfTablesMatchIndices(),
              "low-half lane and group tables disagree with VoxelBlock::index()");

/// refreshMeshSigns() for the voxels of `kLevel` starting at `voxels`. (Not inlined: GCC would
/// keep the counting pass's loads of this level for it, spilled to the stack.)
template <int kLevel>
__attribute__((target("avx2"), noinline)) uint16_t meshSignBitsAvx2(const Voxel* voxels) {
  // Signs by group half: bit 0 low half on y, bit 1 on z.
  unsigned negative[4] = {}, non_negative[4] = {};
  for (int group = 0; group < levelVoxelCount(kLevel) / 8; ++group) {
    const SignLanes s = signLanesAvx2(voxels + 8 * group);
    const int half = groupInLowHalf(kLevel, group, 1) | 2 * groupInLowHalf(kLevel, group, 2);
    negative[half] |= s.negative;
    non_negative[half] |= s.non_negative;
  }
  // Region r holds the voxels in the low half on every axis of r (bit 0 x, 1 y, 2 z).
  uint16_t bits = 0;
  for (int region = 0; region < 8; ++region) {
    const int region_yz = region >> 1;
    unsigned region_negative = 0, region_non_negative = 0;
    for (int half = 0; half < 4; ++half) {
      if ((half & region_yz) != region_yz) continue;
      region_negative |= negative[half];
      region_non_negative |= non_negative[half];
    }
    unsigned lanes = 0xFF;
    for (int axis = 0; axis < 3; ++axis)
      if (region & (1 << axis)) lanes &= kLowHalfLanes[kLevel][axis];
    if (region_negative & lanes) bits |= meshSignBit(region, false);
    if (region_non_negative & lanes) bits |= meshSignBit(region, true);
  }
  return bits;
}

#undef SF_AVX2

}  // namespace

__attribute__((target("avx2"))) void refreshMeshLevelAvx2(const VoxelBlock& block,
                                                          const MeshingParams& params,
                                                          MeshBlockState* state,
                                                          std::vector<Voxel>* fill) {
  static_assert(levelOffset(1) % 8 == 0 && levelOffset(2) % 8 == 0 && levelVoxelCount(2) == 8,
                "every level is whole groups of eight voxels");
  // A level never updated has nothing observed: no need to count it.
  const int observed[kNumLevels] = {block.hasLevel(0) ? countObservedAvx2<0>(block.level(0)) : 0,
                                    block.hasLevel(1) ? countObservedAvx2<1>(block.level(1)) : 0,
                                    block.hasLevel(2) ? countObservedAvx2<2>(block.level(2)) : 0};
  const int level = levelFromObservedCounts(observed, params.level_min_coverage);
  state->level = static_cast<int8_t>(level);
  const Voxel* voxels = refreshSeamFill(block, params, state, fill);
  if (level == 0) state->sign_bits = meshSignBitsAvx2<0>(voxels);
  if (level == 1) state->sign_bits = meshSignBitsAvx2<1>(voxels);
  if (level == 2) state->sign_bits = meshSignBitsAvx2<2>(voxels);
}

#else  // not x86: only the scalar path

void refreshMeshLevelAvx2(const VoxelBlock& block, const MeshingParams& params,
                          MeshBlockState* state, std::vector<Voxel>* fill) {
  refreshMeshLevelScalar(block, params, state, fill);
}

#endif

}  // namespace stereo_fusion
