// MeasurementImage against a per-pixel transcription of its rules, bit for bit, on rows of
// hostile disparities whose widths leave a tail after the eight-pixel steps of the AVX2 path:
// depths exactly at the depth limits and one float beyond, 0, −0, negatives, NaN, ±inf,
// denormals, FLT_MAX; colours from RGB and grey images.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <random>

#include "stereo_fusion/integration/MeasurementImage.h"

using namespace stereo_fusion;

namespace {

constexpr float kFb = 1.0f;  // f·b: z = 1 / d
constexpr float kMinDepth = 0.25f, kMaxDepth = 4.0f;

float referenceDepth(float d) {
  if (!(d > 0.0f) || !std::isfinite(d)) return std::numeric_limits<float>::quiet_NaN();
  const float z = kFb / d;
  return z >= kMinDepth && z <= kMaxDepth ? z : std::numeric_limits<float>::quiet_NaN();
}

float hostileDisparity(std::mt19937& rng) {
  const float inf = std::numeric_limits<float>::infinity();
  const float specials[] = {4.0f,   // z = min exactly
                            0.25f,  // z = max exactly
                            std::nextafter(4.0f, inf),
                            std::nextafter(4.0f, 0.0f),
                            std::nextafter(0.25f, inf),
                            std::nextafter(0.25f, 0.0f),
                            0.0f,
                            -0.0f,
                            -1.0f,
                            1e-40f,
                            -1e-40f,
                            FLT_MAX,
                            inf,
                            -inf,
                            std::numeric_limits<float>::quiet_NaN()};
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  if (unit(rng) < 0.3f)
    return specials[std::uniform_int_distribution<int>(0, std::size(specials) - 1)(rng)];
  return 0.2f + 4.0f * unit(rng);  // mostly inside the depth limits
}

void expectMatchesReference(int width, int height, int channels, std::mt19937& rng,
                            ThreadPool* pool) {
  cv::Mat disparity(height, width, CV_32FC1),
      colour(height, width, channels == 3 ? CV_8UC3 : CV_8UC1);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) disparity.at<float>(v, u) = hostileDisparity(rng);
  for (int v = 0; v < height; ++v)
    for (int b = 0; b < width * channels; ++b)
      colour.ptr<uint8_t>(v)[b] = static_cast<uint8_t>(rng());
  MeasurementImage image;
  image.build(disparity, colour, kFb, kMinDepth, kMaxDepth, pool);
  ASSERT_EQ(image.width(), width);
  ASSERT_EQ(image.height(), height);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const float got = image.depths()[v * width + u],
                  want = referenceDepth(disparity.at<float>(v, u));
      ASSERT_EQ(std::memcmp(&got, &want, sizeof(float)), 0)
          << "width " << width << " pixel (" << u << ", " << v << "): disparity "
          << disparity.at<float>(v, u) << ", depth " << got << " instead of " << want;
      const uint8_t* c = colour.ptr<uint8_t>(v) + u * channels;
      const uint32_t rgb = channels == 3 ? c[0] | c[1] << 8 | c[2] << 16 : c[0] * 0x010101u;
      ASSERT_EQ(image.colours()[v * width + u], rgb) << "pixel (" << u << ", " << v << ")";
    }
}

TEST(MeasurementImage, DepthsAndColoursMatchThePerPixelRules) {
  std::mt19937 rng(4242);
  ThreadPool pool(2);
  for (int width : {1, 7, 8, 9, 15, 16, 37, 640})
    for (int channels : {3, 1})
      ASSERT_NO_FATAL_FAILURE(expectMatchesReference(width, 48, channels, rng, &pool));
}

}  // namespace
