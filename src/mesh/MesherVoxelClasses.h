// Sign classes of runs of voxels as bit masks: what the fast paths decide on before they
// sample anything (the uniform path's row masks, the mixed path's mask rows).
#pragma once
#include <cstddef>
#if defined(__SSE4_1__)
#include <smmintrin.h>
#endif

#include "stereo_fusion/map/Voxel.h"

namespace stereo_fusion::mesher {

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
    out->nonnegative |= static_cast<unsigned>(observed && voxels[i].sdf_m >= 0.0f)
                        << (first_bit + i);
    out->negative |= static_cast<unsigned>(observed && voxels[i].sdf_m < -1e-30f)
                     << (first_bit + i);
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
      const __m128 sdf =
          _mm_insert_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 2, 3, 0)), c, (1 << 6) | (3 << 4));
      const __m128 w123 = _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 0));           // w1 w2 w3 w3
      const __m128 w0011 = _mm_shuffle_ps(a, w123, _MM_SHUFFLE(0, 0, 1, 1));       // w0 w0 w1 w1
      const __m128 weight = _mm_shuffle_ps(w0011, w123, _MM_SHUFFLE(2, 1, 2, 0));  // w0 w1 w2 w3
      const __m128 observed = _mm_cmpgt_ps(weight, zero);
      const unsigned observed_bits = static_cast<unsigned>(_mm_movemask_ps(observed));
      out.unobserved |= (~observed_bits & 0xFu) << first;
      out.nonnegative |=
          static_cast<unsigned>(_mm_movemask_ps(_mm_and_ps(observed, _mm_cmpge_ps(sdf, zero))))
          << first;
      out.negative |= static_cast<unsigned>(
                          _mm_movemask_ps(_mm_and_ps(observed, _mm_cmplt_ps(sdf, tiny_negative))))
                      << first;
    }
    return out;
  }
#endif
  classifyVoxelsScalar(voxels, count, 0, &out);
  return out;
}

}  // namespace stereo_fusion::mesher
