#pragma once
// Horizontal reductions of an AVX2 float vector, for code compiled with target("avx2"). Only
// include from x86 builds; call only when avx2Supported().
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>

namespace stereo_fusion {

/// Smallest of the eight lanes (as min_ps: a NaN lane yields the other operand).
__attribute__((target("avx2"))) inline float horizontalMin(__m256 x) {
  __m128 m = _mm_min_ps(_mm256_castps256_ps128(x), _mm256_extractf128_ps(x, 1));
  m = _mm_min_ps(m, _mm_movehl_ps(m, m));
  return _mm_cvtss_f32(_mm_min_ss(m, _mm_shuffle_ps(m, m, 1)));
}

/// Largest of the eight lanes (as max_ps: a NaN lane yields the other operand).
__attribute__((target("avx2"))) inline float horizontalMax(__m256 x) {
  __m128 m = _mm_max_ps(_mm256_castps256_ps128(x), _mm256_extractf128_ps(x, 1));
  m = _mm_max_ps(m, _mm_movehl_ps(m, m));
  return _mm_cvtss_f32(_mm_max_ss(m, _mm_shuffle_ps(m, m, 1)));
}

}  // namespace stereo_fusion
#endif
