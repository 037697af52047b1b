#include "stereo_fusion/integration/MeasurementImage.h"

#include <cfloat>
#include <limits>

#include "stereo_fusion/util/CpuFeatures.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define STEREO_FUSION_HAVE_AVX2_ROWS 1
#endif

namespace stereo_fusion {
namespace {

// Both row loops vectorise with the baseline SSE and have AVX2 versions, picked at run time
// through avx2Supported() (not target_clones: its IFUNC resolver runs before
// ThreadSanitizer's runtime is up and crashed the TSan build).

// Branch-free so that the compiler vectorises it: the division is done for every pixel and
// its result discarded where the disparity is unusable (no floating-point traps are enabled).
void convertDepthRow(const float* disparity_px, int width, float fb_px_m, float min_depth_m,
                     float max_depth_m, float* depth_m) {
  const float no_measurement = std::numeric_limits<float>::quiet_NaN();
  for (int u = 0; u < width; ++u) {
    const float d = disparity_px[u];
    const float z = fb_px_m / d;
    // d ≤ FLT_MAX is isfinite(d) once d > 0 (rejects +inf and NaN). `&`, not `&&`: every
    // comparison is evaluated, so there is no branch to keep the compiler from vectorising.
    const bool usable = (d > 0.0f) & (d <= FLT_MAX) & (z >= min_depth_m) & (z <= max_depth_m);
    depth_m[u] = usable ? z : no_measurement;
  }
}

#ifdef STEREO_FUSION_HAVE_AVX2_ROWS
// convertDepthRow() eight pixels at a time: the same correctly rounded division and ordered
// comparisons (false on NaN), the same NaN for unusable pixels; the tail goes to the scalar
// loop. (The larger share of build(): a division and four compares per pixel.)
__attribute__((target("avx2"))) void convertDepthRowAvx2(const float* disparity_px, int width,
                                                         float fb_px_m, float min_depth_m,
                                                         float max_depth_m, float* depth_m) {
  const __m256 fb = _mm256_set1_ps(fb_px_m), zero = _mm256_setzero_ps(),
               largest = _mm256_set1_ps(FLT_MAX);
  const __m256 min_depth = _mm256_set1_ps(min_depth_m), max_depth = _mm256_set1_ps(max_depth_m);
  const __m256 no_measurement = _mm256_set1_ps(std::numeric_limits<float>::quiet_NaN());
  int u = 0;
  for (; u + 8 <= width; u += 8) {
    const __m256 d = _mm256_loadu_ps(disparity_px + u);
    const __m256 z = _mm256_div_ps(fb, d);
    __m256 usable =
        _mm256_and_ps(_mm256_cmp_ps(d, zero, _CMP_GT_OQ), _mm256_cmp_ps(d, largest, _CMP_LE_OQ));
    usable = _mm256_and_ps(usable, _mm256_cmp_ps(z, min_depth, _CMP_GE_OQ));
    usable = _mm256_and_ps(usable, _mm256_cmp_ps(z, max_depth, _CMP_LE_OQ));
    _mm256_storeu_ps(depth_m + u, _mm256_blendv_ps(no_measurement, z, usable));
  }
  convertDepthRow(disparity_px + u, width - u, fb_px_m, min_depth_m, max_depth_m, depth_m + u);
}
#endif

void packColourRow(const uint8_t* color, int channels, int width, uint32_t* rgb) {
  if (channels == 1) {
    for (int u = 0; u < width; ++u) rgb[u] = color[u] * 0x010101u;
    return;
  }
  for (int u = 0; u < width; ++u)
    rgb[u] = color[3 * u] | static_cast<uint32_t>(color[3 * u + 1]) << 8 |
             static_cast<uint32_t>(color[3 * u + 2]) << 16;
}

#ifdef STEREO_FUSION_HAVE_AVX2_ROWS
// packColourRow() for RGB eight pixels at a time (GCC's SSE version of the byte shuffle takes
// ~4 instructions per pixel): pixels 0–3 and 4–7 load into one 128-bit lane each, and one
// byte shuffle per lane moves each pixel's R, G, B into bytes 0–2 of its word. Grey rows and
// the tail go to the scalar loop.
__attribute__((target("avx2"))) void packColourRowAvx2(const uint8_t* color, int channels,
                                                       int width, uint32_t* rgb) {
  int u = 0;
  if (channels == 3) {
    const __m256i spread =
        _mm256_setr_epi8(0, 1, 2, -1, 3, 4, 5, -1, 6, 7, 8, -1, 9, 10, 11, -1,  //
                         0, 1, 2, -1, 3, 4, 5, -1, 6, 7, 8, -1, 9, 10, 11, -1);
    // The high lane's 16-byte load reads 4 bytes past pixel u + 7: stop while they are in the row.
    for (; u + 10 <= width; u += 8) {
      const __m256i bytes =
          _mm256_loadu2_m128i(reinterpret_cast<const __m128i*>(color + 3 * (u + 4)),
                              reinterpret_cast<const __m128i*>(color + 3 * u));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(rgb + u), _mm256_shuffle_epi8(bytes, spread));
    }
  }
  packColourRow(color + channels * u, channels, width - u, rgb + u);
}
#endif

}  // namespace

void MeasurementImage::build(const cv::Mat& disparity_px, const cv::Mat& color, float fb_px_m,
                             float min_depth_m, float max_depth_m, ThreadPool* pool) {
  width_ = disparity_px.cols;
  height_ = disparity_px.rows;
  const size_t pixels = static_cast<size_t>(width_) * height_;
  depth_m_.resize(pixels);
  if (!color.empty()) rgb_.resize(pixels);
  auto convert_depth_row = convertDepthRow;
  auto pack_colour_row = packColourRow;
#ifdef STEREO_FUSION_HAVE_AVX2_ROWS
  if (avx2Supported()) {
    convert_depth_row = convertDepthRowAvx2;
    pack_colour_row = packColourRowAvx2;
  }
#endif
  // ~16 rows per chunk: large enough to amortise the claim, small enough to balance.
  pool->parallelFor(static_cast<size_t>(height_), 16, [&](size_t begin, size_t end) {
    for (size_t v = begin; v < end; ++v) {
      const int row = static_cast<int>(v);
      convert_depth_row(disparity_px.ptr<float>(row), width_, fb_px_m, min_depth_m, max_depth_m,
                        &depth_m_[v * width_]);
      if (!color.empty())
        pack_colour_row(color.ptr<uint8_t>(row), color.channels(), width_, &rgb_[v * width_]);
    }
  });
}

void MeasurementImage::build(const StereoFrame& frame, const MeasurementConfig& config,
                             ThreadPool* pool) {
  const StereoCamera& camera = frame.camera;
  build(frame.disparity_px, config.use_color ? frame.color : cv::Mat(),
        static_cast<float>(camera.fx() * camera.baseline()), static_cast<float>(config.min_depth_m),
        static_cast<float>(config.max_depth_m), pool);
  levels_ =
      levelThresholdsFor(config.levels, camera.fx() * camera.baseline(), frame.disparity_step_px);
}

uint64_t MeasurementImage::invalidate(const cv::Mat& reject, ThreadPool* pool) {
  CV_Assert(reject.type() == CV_8UC1 && reject.rows == height_ && reject.cols == width_);
  const float no_measurement = std::numeric_limits<float>::quiet_NaN();
  std::vector<uint32_t> per_row(static_cast<size_t>(height_), 0);
  auto rows = [&](size_t begin, size_t end) {
    for (size_t v = begin; v < end; ++v) {
      const uint8_t* row = reject.ptr<uint8_t>(static_cast<int>(v));
      float* depth = &depth_m_[v * width_];
      uint32_t invalidated = 0;
      // Branch-free, a store to every pixel: the compiler vectorises it.
      for (int u = 0; u < width_; ++u) {
        const bool usable_and_rejected = row[u] != 0 && depth[u] == depth[u];
        invalidated += usable_and_rejected;
        depth[u] = usable_and_rejected ? no_measurement : depth[u];
      }
      per_row[v] = invalidated;
    }
  };
  parallelForOrHere(pool, per_row.size(), 32, rows);
  uint64_t invalidated = 0;
  for (uint32_t n : per_row) invalidated += n;
  return invalidated;
}

}  // namespace stereo_fusion
