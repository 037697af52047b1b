// The AVX2 fusion kernel (fuseBlockAvx2()), held bit-identical to the scalar one
// (FusionKernels.cpp) by FusionReference.* and FusionPreTest.*.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "FusionKernelParts.h"
#include "stereo_fusion/integration/FusionKernels.h"
#include "stereo_fusion/integration/FusionMath.h"
#include "stereo_fusion/integration/SurfaceFuser.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>

#include "stereo_fusion/util/Avx2Reduce.h"
#define STEREO_FUSION_HAVE_AVX2_KERNEL 1
#endif

// No function in this file may be compiled with FMA enabled: GCC (gnu++17) contracts a*b + c
// into one fused operation whenever the target has FMA, which rounds once instead of twice and
// would make the AVX2 kernel disagree with the scalar one. target("avx2") does not enable FMA.

namespace stereo_fusion {

#ifdef STEREO_FUSION_HAVE_AVX2_KERNEL
// ---------------------------------------------------------------------------------------------
// AVX2 kernel. Lanes are eight consecutive voxels of a level's flat array (eq. 3.4): a row of
// level 0, two rows of level 1, all of level 2. The voxel centre is computed as in the scalar
// kernel, ((first + i·ex) + j·ey) + k·ez per coordinate, from per-lane i, j, k terms.

namespace {

#define SF_AVX2 __attribute__((target("avx2"), always_inline)) inline

/// Frame constants broadcast to all lanes, once per block.
struct Avx2Constants {
  __m256 fx, fy, cx, cy, u_end, v_end, minus_half, half, zero, one, nan;
  __m256 level1_min_depth, level2_min_depth, depth_weight_reference, max_weight, max_channel,
      contradicted_keep;
  __m256i width, height;
};

SF_AVX2 Avx2Constants avx2Constants(const FusionFrame& f) {
  Avx2Constants c;
  c.fx = _mm256_set1_ps(f.fx_px);
  c.fy = _mm256_set1_ps(f.fy_px);
  c.cx = _mm256_set1_ps(f.cx_px);
  c.cy = _mm256_set1_ps(f.cy_px);
  c.u_end = _mm256_set1_ps(f.u_end_px);
  c.v_end = _mm256_set1_ps(f.v_end_px);
  c.minus_half = _mm256_set1_ps(-0.5f);
  c.half = _mm256_set1_ps(0.5f);
  c.zero = _mm256_setzero_ps();
  c.one = _mm256_set1_ps(1.0f);
  c.nan = _mm256_set1_ps(NAN);
  c.level1_min_depth = _mm256_set1_ps(f.level1_min_depth_m);
  c.level2_min_depth = _mm256_set1_ps(f.level2_min_depth_m);
  c.depth_weight_reference = _mm256_set1_ps(f.depth_weight_reference_m);
  c.max_weight = _mm256_set1_ps(f.max_weight);
  c.max_channel = _mm256_set1_ps(255.0f);
  c.contradicted_keep = _mm256_set1_ps(f.contradicted_keep);
  c.width = _mm256_set1_epi32(f.width_px);
  c.height = _mm256_set1_epi32(f.height_px);
  return c;
}

/// Measurement-level dependent band half-width and δ for one voxel level.
struct Avx2Band {
  __m256 truncation[kNumLevels];
  __m256 delta[kNumLevels];
};

SF_AVX2 Avx2Band avx2Band(const FusionFrame& f, int level) {
  Avx2Band b;
  for (int m = 0; m < kNumLevels; ++m) {
    b.truncation[m] = _mm256_set1_ps(f.levels[level].truncation_m[m]);
    b.delta[m] = _mm256_set1_ps(f.delta_m[m]);
  }
  return b;
}

/// Eight consecutive voxels (96 bytes) as one vector per field.
struct Avx2Voxels {
  __m256 sdf_m, weight;
  __m256i rgb;  ///< r | g << 8 | b << 16 | reserved << 24: the Voxel's last four bytes
};

// The 96 bytes load as three vectors of dwords; dword 3n + q is field q of voxel n, in vector
// (3n + q) / 8 at lane (3n + q) mod 8. As 3 is invertible modulo 8, every lane position holds
// each field in exactly one of the three vectors: two blends collect a field, one permutation
// (n ↦ lane) puts voxel n into lane n. Storing runs the same steps backwards.
SF_AVX2 Avx2Voxels loadVoxels(const Voxel* voxels) {
  static_assert(sizeof(Voxel) == 12 && offsetof(Voxel, weight) == 4 && offsetof(Voxel, r) == 8,
                "the AVX2 kernel reads voxels as {sdf, weight, rgb} dword triples");
  const float* dwords = reinterpret_cast<const float*>(voxels);
  const __m256 v0 = _mm256_loadu_ps(dwords), v1 = _mm256_loadu_ps(dwords + 8),
               v2 = _mm256_loadu_ps(dwords + 16);
  Avx2Voxels v;
  v.sdf_m =
      _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(v0, v1, 0b10010010), v2, 0b00100100),
                               _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
  v.weight =
      _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(v0, v1, 0b00100100), v2, 0b01001001),
                               _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6));
  v.rgb = _mm256_castps_si256(
      _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(v0, v1, 0b01001001), v2, 0b10010010),
                               _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7)));
  return v;
}

SF_AVX2 void storeVoxels(const Avx2Voxels& v, Voxel* voxels) {
  const __m256 sdf = _mm256_permutevar8x32_ps(v.sdf_m, _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
  const __m256 weight =
      _mm256_permutevar8x32_ps(v.weight, _mm256_setr_epi32(5, 0, 3, 6, 1, 4, 7, 2));
  const __m256 rgb = _mm256_permutevar8x32_ps(_mm256_castsi256_ps(v.rgb),
                                              _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
  float* dwords = reinterpret_cast<float*>(voxels);
  _mm256_storeu_ps(dwords,
                   _mm256_blend_ps(_mm256_blend_ps(sdf, weight, 0b10010010), rgb, 0b00100100));
  _mm256_storeu_ps(dwords + 8,
                   _mm256_blend_ps(_mm256_blend_ps(sdf, weight, 0b00100100), rgb, 0b01001001));
  _mm256_storeu_ps(dwords + 16,
                   _mm256_blend_ps(_mm256_blend_ps(sdf, weight, 0b01001001), rgb, 0b10010010));
}

/// One colour channel, (w_old·c_old + w·c)/W rounded as fuseMeasurement()'s blend, from and to
/// byte `kShift` / 8 of each lane.
template <int kShift>
SF_AVX2 __m256i blendChannel(const Avx2Constants& c, __m256i old_rgb, __m256i observed_rgb,
                             __m256 old_weight, __m256 weight, __m256 weight_sum) {
  const __m256i byte = _mm256_set1_epi32(0xff);
  const __m256 old_c =
      _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(old_rgb, kShift), byte));
  const __m256 new_c =
      _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(observed_rgb, kShift), byte));
  const __m256 mean = _mm256_div_ps(
      _mm256_add_ps(_mm256_mul_ps(old_weight, old_c), _mm256_mul_ps(weight, new_c)), weight_sum);
  // std::clamp(mean + 0.5, 0, 255): max_ps returns its second operand for NaN, giving 0 as the
  // scalar conversion of NaN does after truncation to a byte.
  const __m256 clamped =
      _mm256_min_ps(_mm256_max_ps(_mm256_add_ps(mean, c.half), c.zero), c.max_channel);
  return _mm256_slli_epi32(_mm256_cvttps_epi32(clamped), kShift);
}

/// Eq. 3.8–3.9 (fuseMeasurement(), same operation order) for the voxels of the `keep` lanes;
/// the others are written back unchanged.
SF_AVX2 void updateEightAvx2(const FusionFrame& f, const Avx2Constants& c, __m256 keep, __m256 sdf,
                             __m256 truncation, __m256 weight, __m256i pixel, Voxel* voxels) {
  Avx2Voxels old = loadVoxels(voxels);
  const __m256 stored_weight = old.weight;  // written back in the lanes not updated
  // std::max(sdf, −Φ); −Φ flips the sign bit as scalar negation does.
  const __m256 minus_truncation = _mm256_xor_ps(truncation, _mm256_set1_ps(-0.0f));
  const __m256 clamped =
      _mm256_blendv_ps(sdf, minus_truncation, _mm256_cmp_ps(sdf, minus_truncation, _CMP_LT_OQ));
  // weightBeforeUpdate(): |D − d| clears the sign bit as std::abs does.
  const __m256 disagreement =
      _mm256_andnot_ps(_mm256_set1_ps(-0.0f), _mm256_sub_ps(old.sdf_m, clamped));
  old.weight = _mm256_blendv_ps(old.weight, _mm256_mul_ps(old.weight, c.contradicted_keep),
                                _mm256_cmp_ps(disagreement, truncation, _CMP_GT_OQ));
  const __m256 weight_sum = _mm256_add_ps(old.weight, weight);
  Avx2Voxels updated;
  updated.sdf_m = _mm256_div_ps(
      _mm256_add_ps(_mm256_mul_ps(old.weight, old.sdf_m), _mm256_mul_ps(weight, clamped)),
      weight_sum);
  // std::min(W + w, W_max)
  updated.weight = _mm256_blendv_ps(weight_sum, c.max_weight,
                                    _mm256_cmp_ps(c.max_weight, weight_sum, _CMP_LT_OQ));
  updated.rgb = old.rgb;
  if (f.rgb != nullptr) {
    const __m256i observed =
        _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(f.rgb),
                                    pixel, _mm256_castps_si256(keep), 4);
    __m256i rgb = _mm256_and_si256(
        old.rgb, _mm256_set1_epi32(static_cast<int>(0xff000000u)));  // reserved byte
    rgb =
        _mm256_or_si256(rgb, blendChannel<0>(c, old.rgb, observed, old.weight, weight, weight_sum));
    rgb =
        _mm256_or_si256(rgb, blendChannel<8>(c, old.rgb, observed, old.weight, weight, weight_sum));
    rgb = _mm256_or_si256(rgb,
                          blendChannel<16>(c, old.rgb, observed, old.weight, weight, weight_sum));
    updated.rgb = rgb;
  }
  updated.sdf_m = _mm256_blendv_ps(old.sdf_m, updated.sdf_m, keep);
  updated.weight = _mm256_blendv_ps(stored_weight, updated.weight, keep);
  updated.rgb = _mm256_castps_si256(
      _mm256_blendv_ps(_mm256_castsi256_ps(old.rgb), _mm256_castsi256_ps(updated.rgb), keep));
  storeVoxels(updated, voxels);
}

/// The value of `by_level` for the measurement level of each lane: 2 where z reaches the
/// level-2 threshold, else 1 where it reaches the level-1 one, else 0 (levelForDepth()).
SF_AVX2 __m256 selectByLevel(const __m256 by_level[kNumLevels], __m256 reaches1, __m256 reaches2) {
  return _mm256_blendv_ps(_mm256_blendv_ps(by_level[0], by_level[1], reaches1), by_level[2],
                          reaches2);
}

/// Eq. 3.11–3.15 and 3.10 for eight voxels at camera points (px, py, pz); fuses the observed
/// ones into voxels[0..7]. `finer_updated`: measurements of the next coarser level update this
/// one too (measurementUpdatesLevel() with the level allocated). Returns the number of updates.
SF_AVX2 uint64_t fuseEightAvx2(const FusionFrame& f, const Avx2Constants& c, const Avx2Band& band,
                               int level, bool finer_updated, __m256 px, __m256 py, __m256 pz,
                               Voxel* voxels) {
  const __m256 in_front = _mm256_cmp_ps(pz, c.zero, _CMP_GT_OQ);
  if (_mm256_testz_ps(in_front, in_front)) return 0;
  // Eq. 3.12–3.14, as fx·x/z + cx in the scalar order (no reciprocal: x/z ≠ x·(1/z)).
  const __m256 u = _mm256_add_ps(_mm256_div_ps(_mm256_mul_ps(c.fx, px), pz), c.cx);
  const __m256 v = _mm256_add_ps(_mm256_div_ps(_mm256_mul_ps(c.fy, py), pz), c.cy);
  __m256 inside = _mm256_and_ps(in_front, _mm256_cmp_ps(u, c.minus_half, _CMP_GE_OQ));
  inside = _mm256_and_ps(inside, _mm256_cmp_ps(v, c.minus_half, _CMP_GE_OQ));
  inside = _mm256_and_ps(inside, _mm256_cmp_ps(u, c.u_end, _CMP_LT_OQ));
  inside = _mm256_and_ps(inside, _mm256_cmp_ps(v, c.v_end, _CMP_LT_OQ));
  if (_mm256_testz_ps(inside, inside)) return 0;
  const __m256i iu = _mm256_cvttps_epi32(_mm256_floor_ps(_mm256_add_ps(u, c.half)));
  const __m256i iv = _mm256_cvttps_epi32(_mm256_floor_ps(_mm256_add_ps(v, c.half)));
  // iu ∈ [0, width) and iv ∈ [0, height), in integers as in the scalar kernel.
  const __m256i minus_one = _mm256_set1_epi32(-1);
  __m256i in_image = _mm256_castps_si256(inside);
  in_image = _mm256_and_si256(in_image, _mm256_cmpgt_epi32(iu, minus_one));
  in_image = _mm256_and_si256(in_image, _mm256_cmpgt_epi32(iv, minus_one));
  in_image = _mm256_and_si256(in_image, _mm256_cmpgt_epi32(c.width, iu));
  in_image = _mm256_and_si256(in_image, _mm256_cmpgt_epi32(c.height, iv));
  const __m256i pixel = _mm256_add_epi32(_mm256_mullo_epi32(iv, c.width), iu);
  // Lanes outside the image read nothing and get NaN: "no measurement".
  const __m256 surface_depth =
      _mm256_mask_i32gather_ps(c.nan, f.depth_m, pixel, _mm256_castsi256_ps(in_image), 4);
  __m256 keep = _mm256_cmp_ps(surface_depth, surface_depth, _CMP_ORD_Q);
  const __m256 reaches1 = _mm256_cmp_ps(surface_depth, c.level1_min_depth, _CMP_GE_OQ);
  const __m256 reaches2 = _mm256_cmp_ps(surface_depth, c.level2_min_depth, _CMP_GE_OQ);
  // Too fine for the measurement (measurementUpdatesLevel(): level < measurement level, unless
  // the level is the next finer one and allocated). Level 2 iff reaches2, level 1 iff
  // reaches1 and not reaches2.
  if (level == 0)
    keep = _mm256_andnot_ps(finer_updated ? reaches2 : _mm256_or_ps(reaches1, reaches2), keep);
  if (level == 1 && !finer_updated) keep = _mm256_andnot_ps(reaches2, keep);
  if (_mm256_testz_ps(keep, keep)) return 0;
  const __m256 truncation = selectByLevel(band.truncation, reaches1, reaches2);
  // Eq. 3.15: sqrt(x² + y² + z²) · (1 − z_s / z), in signedDistanceAlongRay()'s order.
  const __m256 norm = _mm256_sqrt_ps(_mm256_add_ps(
      _mm256_add_ps(_mm256_mul_ps(px, px), _mm256_mul_ps(py, py)), _mm256_mul_ps(pz, pz)));
  const __m256 sdf = _mm256_mul_ps(norm, _mm256_sub_ps(c.one, _mm256_div_ps(surface_depth, pz)));
  // !(sdf > Φ): far behind the surface is unobserved (unordered compares keep NaN lanes, as
  // the scalar test does; the weight test below drops them).
  keep = _mm256_and_ps(keep, _mm256_cmp_ps(sdf, truncation, _CMP_NGT_UQ));
  if (_mm256_testz_ps(keep, keep)) return 0;
  // measurementWeight() for lanes with !(sdf > Φ).
  __m256 weight = c.one;
  if (f.weight_mode != WeightMode::kConstant) {
    const __m256 delta = selectByLevel(band.delta, reaches1, reaches2);
    const __m256 falloff =
        _mm256_div_ps(_mm256_sub_ps(truncation, sdf), _mm256_sub_ps(truncation, delta));
    weight = _mm256_blendv_ps(falloff, c.one, _mm256_cmp_ps(sdf, delta, _CMP_LT_OQ));
    if (f.weight_mode == WeightMode::kDepthAware) {
      const __m256 ratio = _mm256_div_ps(c.depth_weight_reference, surface_depth);
      weight = _mm256_mul_ps(_mm256_mul_ps(weight, ratio), ratio);
    }
  }
  if (finer_updated) {  // lanes whose measurement is of the next coarser level:
                        // kFinerLevelWeightScale
    const __m256 coarser = level == 0 ? reaches1 : reaches2;
    weight = _mm256_blendv_ps(weight, _mm256_mul_ps(weight, _mm256_set1_ps(kFinerLevelWeightScale)),
                              coarser);
  }
  keep = _mm256_and_ps(keep, _mm256_cmp_ps(weight, c.zero, _CMP_GT_OQ));
  const int lanes = _mm256_movemask_ps(keep);
  if (lanes == 0) return 0;
  updateEightAvx2(f, c, keep, sdf, truncation, weight, pixel, voxels);
  return static_cast<uint64_t>(__builtin_popcount(static_cast<unsigned>(lanes)));
}

/// Per-coordinate bound on the float error of a voxel centre of `level` in a block whose first
/// centre is `first`: the kernel rounds ≤ 6 times (first + i·ex, j·ey, k·ez, two sums), and so
/// do the group corners of groupMayBeUpdated() (edge = 7·ex, first + k·ez, three sums), each
/// time by ≤ 2^-24 of a number no larger than |first| + side·(|ex| + |ey| + |ez|): 4e-6 per
/// metre of that is over 5× their sum (12 · 2^-24 ≈ 7.2e-7).
double positionErrorBound(const FusionFrame::Level& geometry, const Eigen::Vector3f& first,
                          int level) {
  const double magnitude_m =
      first.cwiseAbs().maxCoeff() + levelSide(level) * (geometry.ex_m.cwiseAbs().maxCoeff() +
                                                        geometry.ey_m.cwiseAbs().maxCoeff() +
                                                        geometry.ez_m.cwiseAbs().maxCoeff());
  return 4e-6 * magnitude_m + 1e-6;
}

/// Conservative pre-test for a group of level-0 voxels whose centres span the parallelepiped
/// first + [0, 1]·edge_a + [0, 1]·edge_b + [0, 1]·edge_c: false only if the frame provably
/// updates none of them, i.e. every voxel projects outside the image, or onto a pixel with no
/// measurement, one too coarse for level 0 (coarser than level 0, or with `finer_updated`
/// than level 1), or one farther than Φ in front of it
/// (sdf > Φ, eq. 3.15; sufficient: z_c − z > Φ since ‖x_c‖ ≥ z_c). The projection of a convex
/// set with z_c > 0 has its extreme x/z, y/z at the corners, so eight corners bound the
/// footprint; the margins below cover the float roundings of both the corners and the
/// kernel's own per-voxel arithmetic, each many times over.
///
/// `position_error_m` bounds, per coordinate, how far any voxel centre of the group as the
/// kernel computes it, and any corner as computed here, are from the exact points
/// (positionErrorBound()).
SF_AVX2 bool groupMayBeUpdated(const FusionFrame& f, bool finer_updated,
                               const Eigen::Vector3f& first, const Eigen::Vector3f& edge_a,
                               const Eigen::Vector3f& edge_b, const Eigen::Vector3f& edge_c,
                               double position_error_m) {
  const __m256 in_a = _mm256_castsi256_ps(_mm256_setr_epi32(0, -1, 0, -1, 0, -1, 0, -1));
  const __m256 in_b = _mm256_castsi256_ps(_mm256_setr_epi32(0, 0, -1, -1, 0, 0, -1, -1));
  const __m256 in_c = _mm256_castsi256_ps(_mm256_setr_epi32(0, 0, 0, 0, -1, -1, -1, -1));
  __m256 corner[3];
  for (int axis = 0; axis < 3; ++axis)
    corner[axis] = _mm256_add_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_set1_ps(first[axis]),
                                    _mm256_and_ps(in_a, _mm256_set1_ps(edge_a[axis]))),
                      _mm256_and_ps(in_b, _mm256_set1_ps(edge_b[axis]))),
        _mm256_and_ps(in_c, _mm256_set1_ps(edge_c[axis])));
  const double z_min_m = horizontalMin(corner[2]) - position_error_m;
  const double z_max_m = horizontalMax(corner[2]) + position_error_m;
  if (!(z_min_m > 1e-3)) return true;  // near or behind the camera: no safe bound, visit all
  const __m256 qx = _mm256_div_ps(corner[0], corner[2]), qy = _mm256_div_ps(corner[1], corner[2]);
  const double qx_min = horizontalMin(qx), qx_max = horizontalMax(qx);
  const double qy_min = horizontalMin(qy), qy_max = horizontalMax(qy);
  // x/z of any voxel lies in [qx_min, qx_max] widened by its position error and roundings.
  const double q_abs = std::max(std::max(std::fabs(qx_min), std::fabs(qx_max)),
                                std::max(std::fabs(qy_min), std::fabs(qy_max)));
  if (!std::isfinite(q_abs)) return true;  // no bound from a non-finite point: visit all
  const double q_error = position_error_m * (1.0 + q_abs) / z_min_m + 1e-6 * q_abs;
  // Pixel range that any voxel's nearest pixel floor(u + 0.5) (u = fx·x/z + cx) can take.
  auto pixel_range = [&](double focal_px, double centre_px, double q_lo, double q_hi, int size_px,
                         int* lo, int* hi) {
    const double a = focal_px * (q_lo - q_error), b = focal_px * (q_hi + q_error);
    const double slack_px =
        1e-5 * (std::fabs(focal_px) * (q_abs + q_error) + std::fabs(centre_px)) + 1e-2;
    const double first_px = std::floor(std::min(a, b) + centre_px - slack_px + 0.5);
    const double last_px = std::floor(std::max(a, b) + centre_px + slack_px + 0.5);
    if (last_px < 0.0 || first_px > size_px - 1) return false;
    *lo = first_px < 0.0 ? 0 : static_cast<int>(first_px);
    *hi = last_px > size_px - 1 ? size_px - 1 : static_cast<int>(last_px);
    return true;
  };
  int u0, u1, v0, v1;
  if (!pixel_range(f.fx_px, f.cx_px, qx_min, qx_max, f.width_px, &u0, &u1))
    return false;  // outside
  if (!pixel_range(f.fy_px, f.cy_px, qy_min, qy_max, f.height_px, &v0, &v1)) return false;
  // Level-0 measurements update level-0 voxels, and level-1 ones where the block holds level 0
  // (finer_updated): the widest of their bands.
  const double truncation_m =
      finer_updated ? std::max(f.levels[0].truncation_m[0], f.levels[0].truncation_m[1])
                    : f.levels[0].truncation_m[0];
  const DepthTiles::Measurements which =
      finer_updated ? DepthTiles::Measurements::kLevel0And1 : DepthTiles::Measurements::kLevel0;
  // sdf as the kernel rounds it is ≥ (z_c − z)(1 − 1e-6) − 1e-7·z_c: a margin of 1e-4 m plus
  // 1e-5 of the depths covers that many times over.
  const double limit_m = z_min_m - truncation_m - (1e-4 + 1e-5 * (truncation_m + z_max_m));
  const float limit_f = std::nextafter(static_cast<float>(limit_m), -INFINITY);  // ≤ limit_m
  const int tile = DepthTiles::kTilePx;
  return !f.tiles->allBelow(which, u0 / tile, v0 / tile, u1 / tile, v1 / tile, limit_f);
}

/// Per-level lane terms of the voxel centres: first + i·ex for i = 0..7 (lanes beyond the
/// level's side are unused), and j·ey, k·ez likewise, each coordinate in one vector.
struct Avx2Steps {
  __m256 a[3], b[3], c[3];
};

SF_AVX2 Avx2Steps avx2Steps(const FusionFrame::Level& geometry, const Eigen::Vector3f& first) {
  const __m256 index = _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7);
  Avx2Steps s;
  for (int axis = 0; axis < 3; ++axis) {
    s.a[axis] = _mm256_add_ps(_mm256_set1_ps(first[axis]),
                              _mm256_mul_ps(index, _mm256_set1_ps(geometry.ex_m[axis])));
    s.b[axis] = _mm256_mul_ps(index, _mm256_set1_ps(geometry.ey_m[axis]));
    s.c[axis] = _mm256_mul_ps(index, _mm256_set1_ps(geometry.ez_m[axis]));
  }
  return s;
}

/// Level 0, one row (fixed j, k) per step: the j and k terms are the same in every lane.
/// With f.tiles, the whole level and then each k-slice (eight steps) are first put to
/// groupMayBeUpdated(): at 2 cm it drops about two thirds of the level-0 visits and a fifth of
/// the remaining slices. (Tried at level 1 too: per block it skipped ~23% of the visits, per
/// slice ~10%, and cost more CPU time than it saved.)
__attribute__((target("avx2"), noinline)) uint64_t fuseLevel0Avx2(
    const FusionFrame& f, const Avx2Constants& c, const Avx2Band& band, bool finer_updated,
    const Avx2Steps& s, const FusionFrame::Level& geometry, const Eigen::Vector3f& first,
    Voxel* voxels) {
  const bool pre_test = f.tiles != nullptr;
  const Eigen::Vector3f row_edge = static_cast<float>(kFinestSide - 1) * geometry.ex_m;
  const Eigen::Vector3f slice_edge = static_cast<float>(kFinestSide - 1) * geometry.ey_m;
  const Eigen::Vector3f depth_edge = static_cast<float>(kFinestSide - 1) * geometry.ez_m;
  const double position_error_m = pre_test ? positionErrorBound(geometry, first, 0) : 0.0;
  if (pre_test && !groupMayBeUpdated(f, finer_updated, first, row_edge, slice_edge, depth_edge,
                                     position_error_m))
    return 0;  // no voxel of level 0 can change
  alignas(32) float j_terms[3][8], k_terms[3][8];
  for (int axis = 0; axis < 3; ++axis) {
    _mm256_store_ps(j_terms[axis], s.b[axis]);
    _mm256_store_ps(k_terms[axis], s.c[axis]);
  }
  uint64_t updates = 0;
  for (int k = 0; k < kFinestSide; ++k) {
    if (pre_test &&
        !groupMayBeUpdated(f, finer_updated, first + static_cast<float>(k) * geometry.ez_m,
                           row_edge, slice_edge, Eigen::Vector3f::Zero(), position_error_m))
      continue;  // no voxel of this k-slice (eight steps) can change
    for (int j = 0; j < kFinestSide; ++j) {
      __m256 p[3];
      for (int axis = 0; axis < 3; ++axis)
        p[axis] = _mm256_add_ps(_mm256_add_ps(s.a[axis], _mm256_set1_ps(j_terms[axis][j])),
                                _mm256_set1_ps(k_terms[axis][k]));
      updates += fuseEightAvx2(f, c, band, 0, finer_updated, p[0], p[1], p[2],
                               &voxels[kFinestSide * (j + kFinestSide * k)]);
    }
  }
  return updates;
}

/// Level 1, two rows per step: lane n is voxel (n mod 4, 2h + n / 4, k) of step 2k + h.
__attribute__((target("avx2"), noinline)) uint64_t fuseLevel1Avx2(
    const FusionFrame& f, const Avx2Constants& c, const Avx2Band& band, bool finer_updated,
    const Avx2Steps& s, Voxel* voxels) {
  __m256 i_terms[3], j_terms[2][3];
  for (int axis = 0; axis < 3; ++axis) {
    i_terms[axis] = _mm256_permutevar8x32_ps(s.a[axis], _mm256_setr_epi32(0, 1, 2, 3, 0, 1, 2, 3));
    j_terms[0][axis] =
        _mm256_permutevar8x32_ps(s.b[axis], _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1));
    j_terms[1][axis] =
        _mm256_permutevar8x32_ps(s.b[axis], _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3));
  }
  uint64_t updates = 0;
  for (int k = 0; k < levelSide(1); ++k) {
    for (int h = 0; h < 2; ++h) {
      __m256 p[3];
      for (int axis = 0; axis < 3; ++axis)
        p[axis] = _mm256_add_ps(_mm256_add_ps(i_terms[axis], j_terms[h][axis]),
                                _mm256_permutevar8x32_ps(s.c[axis], _mm256_set1_epi32(k)));
      updates +=
          fuseEightAvx2(f, c, band, 1, finer_updated, p[0], p[1], p[2], &voxels[8 * (2 * k + h)]);
    }
  }
  return updates;
}

/// Level 2 in one step: lane n is voxel (n mod 2, (n / 2) mod 2, n / 4).
__attribute__((target("avx2"), noinline)) uint64_t fuseLevel2Avx2(const FusionFrame& f,
                                                                  const Avx2Constants& c,
                                                                  const Avx2Band& band,
                                                                  const Avx2Steps& s,
                                                                  Voxel* voxels) {
  __m256 p[3];
  for (int axis = 0; axis < 3; ++axis)
    p[axis] = _mm256_add_ps(
        _mm256_add_ps(
            _mm256_permutevar8x32_ps(s.a[axis], _mm256_setr_epi32(0, 1, 0, 1, 0, 1, 0, 1)),
            _mm256_permutevar8x32_ps(s.b[axis], _mm256_setr_epi32(0, 0, 1, 1, 0, 0, 1, 1))),
        _mm256_permutevar8x32_ps(s.c[axis], _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1)));
  return fuseEightAvx2(f, c, band, 2, false, p[0], p[1], p[2], voxels);
}

}  // namespace

__attribute__((target("avx2"))) uint64_t fuseBlockAvx2(const FusionFrame& f,
                                                       const BlockOctree& octree,
                                                       VoxelBlock* block) {
  static_assert(kNumLevels == 3 && levelVoxelCount(2) == 8,
                "one step per level-2 block, two rows per level-1 step");
  const Eigen::Vector3f origin_c = fusion_kernels::blockOriginInCamera(f, octree, block->key);
  const Avx2Constants c = avx2Constants(f);
  uint64_t updates = 0;
  for (int level = fusion_kernels::firstLevelToVisit(f, origin_c, *block); level < kNumLevels;
       ++level) {
    const FusionFrame::Level& geometry = f.levels[level];
    const Eigen::Vector3f first = origin_c + 0.5f * (geometry.ex_m + geometry.ey_m + geometry.ez_m);
    const Avx2Steps s = avx2Steps(geometry, first);
    const Avx2Band band = avx2Band(f, level);
    // Whether the next coarser level's measurements update this one (before this visit).
    const bool finer_updated =
        level + 1 < kNumLevels &&
        measurementUpdatesLevel(level + 1, level, block->hasLevel(level), f.update_allocated_finer);
    fusion_kernels::LevelTarget target(block, level);
    Voxel* voxels = target.voxels();
    if (level == 0)
      updates +=
          target.commit(fuseLevel0Avx2(f, c, band, finer_updated, s, geometry, first, voxels));
    if (level == 1) updates += target.commit(fuseLevel1Avx2(f, c, band, finer_updated, s, voxels));
    if (level == 2) updates += target.commit(fuseLevel2Avx2(f, c, band, s, voxels));
  }
  return updates;
}

#undef SF_AVX2

#endif

}  // namespace stereo_fusion
