// DepthToDisparity: REP 118 depth images as the disparity of a virtual stereo rig, with
// hand-worked numbers. fx = 500 px, B = 0.05 m: fx·B = 25 px·m, so d = 25 / z.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "stereo_fusion/camera/DepthToDisparity.h"
#include "stereo_fusion/camera/StereoCamera.h"

using namespace stereo_fusion;

namespace {

constexpr double kFx = 500.0;

DepthToDisparity converter() {
  DepthConversionConfig config;
  config.baseline_m = 0.05;
  return DepthToDisparity(config);
}

/// `values` as a one-row image of `encoding`, host byte order, with `pad` spare bytes per row.
template <typename T>
DepthImageView view(const std::string& encoding, const std::vector<T>& values,
                    std::vector<uint8_t>* bytes, int rows = 1, size_t pad = 0) {
  const int width = static_cast<int>(values.size()) / rows;
  const size_t step = width * sizeof(T) + pad;
  bytes->assign(step * rows, 0xAB);
  for (int v = 0; v < rows; ++v)
    std::memcpy(bytes->data() + v * step, values.data() + v * width, width * sizeof(T));
  DepthImageView view;
  view.encoding = encoding;
  view.width = width;
  view.height = rows;
  view.step_bytes = step;
  view.big_endian = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;
  view.data = bytes->data();
  view.size_bytes = bytes->size();
  return view;
}

}  // namespace

TEST(DepthToDisparity, MillimetresHandWorkedWithZeroInvalid) {
  // 1250 mm → 25/1.25 = 20 px; 2500 mm → 10 px; 500 mm → 50 px; 0 mm → no measurement (0);
  // 65535 mm → 25/65.535 = 0.381475...
  std::vector<uint8_t> bytes;
  for (const std::string encoding : {"16UC1", "mono16"}) {
    cv::Mat d;
    std::string error;
    ASSERT_TRUE(converter().convert(view<uint16_t>(encoding, {1250, 2500, 500, 0, 65535}, &bytes),
                                    kFx, &d, &error))
        << error;
    ASSERT_EQ(d.type(), CV_32FC1);
    ASSERT_EQ(d.cols, 5);
    EXPECT_FLOAT_EQ(d.at<float>(0, 0), 20.0f);
    EXPECT_FLOAT_EQ(d.at<float>(0, 1), 10.0f);
    EXPECT_FLOAT_EQ(d.at<float>(0, 2), 50.0f);
    EXPECT_EQ(d.at<float>(0, 3), 0.0f);
    EXPECT_FLOAT_EQ(d.at<float>(0, 4), static_cast<float>(25.0 / 65.535));
  }
}

TEST(DepthToDisparity, MetresHandWorkedWithNonFiniteAndNonPositiveInvalid) {
  // 2 m → 12.5 px, 0.5 m → 50 px, 4 m → 6.25 px; NaN, ±inf, 0 and −1 m → 0.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<uint8_t> bytes;
  cv::Mat d;
  std::string error;
  ASSERT_TRUE(converter().convert(
      view<float>("32FC1", {2.0f, 0.5f, 4.0f, nan, inf, -inf, 0.0f, -1.0f}, &bytes), kFx, &d,
      &error))
      << error;
  EXPECT_FLOAT_EQ(d.at<float>(0, 0), 12.5f);
  EXPECT_FLOAT_EQ(d.at<float>(0, 1), 50.0f);
  EXPECT_FLOAT_EQ(d.at<float>(0, 2), 6.25f);
  for (int u = 3; u < 8; ++u) EXPECT_EQ(d.at<float>(0, u), 0.0f) << "column " << u;
}

TEST(DepthToDisparity, TheCoreGetsTheMeasuredDepthBack) {
  // The core reads z = fx·B/d with the camera's baseline: the virtual rig's B comes back out.
  const StereoCamera camera = *StereoCamera::create(4, 1, kFx, kFx, 2, 0, 0.05);
  std::vector<uint8_t> bytes;
  cv::Mat d;
  std::string error;
  ASSERT_TRUE(
      converter().convert(view<float>("32FC1", {0.3f, 1.7f, 3.1f, 7.9f}, &bytes), kFx, &d, &error));
  const float depths[] = {0.3f, 1.7f, 3.1f, 7.9f};
  for (int u = 0; u < 4; ++u)
    EXPECT_NEAR(camera.depthFromDisparity(d.at<float>(0, u)), depths[u], 1e-6 * depths[u]);
}

TEST(DepthToDisparity, RowPaddingAndBigEndianBytesAreRead) {
  // Two rows of 2 values, 3 spare bytes per row; then the same values big-endian.
  std::vector<uint8_t> bytes;
  DepthImageView padded = view<uint16_t>("16UC1", {1250, 0, 2500, 500}, &bytes, 2, 3);
  cv::Mat d;
  std::string error;
  ASSERT_TRUE(converter().convert(padded, kFx, &d, &error)) << error;
  ASSERT_EQ(d.rows, 2);
  EXPECT_FLOAT_EQ(d.at<float>(0, 0), 20.0f);
  EXPECT_EQ(d.at<float>(0, 1), 0.0f);
  EXPECT_FLOAT_EQ(d.at<float>(1, 0), 10.0f);
  EXPECT_FLOAT_EQ(d.at<float>(1, 1), 50.0f);

  // 1250 = 0x04E2 written most significant byte first.
  const uint8_t big[] = {0x04, 0xE2};
  DepthImageView swapped;
  swapped.encoding = "16UC1";
  swapped.width = 1;
  swapped.height = 1;
  swapped.step_bytes = 2;
  swapped.big_endian = true;
  swapped.data = big;
  swapped.size_bytes = 2;
  ASSERT_TRUE(converter().convert(swapped, kFx, &d, &error)) << error;
  EXPECT_FLOAT_EQ(d.at<float>(0, 0), 20.0f);
}

TEST(DepthToDisparity, AWrongEncodingOrShortDataIsRefusedWithItsReason) {
  std::vector<uint8_t> bytes;
  const cv::Mat untouched(1, 1, CV_32FC1, cv::Scalar(7.0f));
  cv::Mat d = untouched;
  std::string error;
  EXPECT_FALSE(converter().convert(view<uint8_t>("rgb8", {1, 2, 3}, &bytes), kFx, &d, &error));
  EXPECT_NE(error.find("'rgb8'"), std::string::npos) << error;
  EXPECT_NE(error.find("16UC1"), std::string::npos) << error;
  EXPECT_NE(error.find("32FC1"), std::string::npos) << error;
  // A float image called 16UC1 is read as what it says; 8UC1 depth is refused.
  EXPECT_FALSE(converter().convert(view<uint8_t>("8UC1", {1, 2}, &bytes), kFx, &d, &error));

  DepthImageView short_data = view<uint16_t>("16UC1", {1000, 1000, 1000, 1000}, &bytes, 2);
  short_data.size_bytes -= 1;
  EXPECT_FALSE(converter().convert(short_data, kFx, &d, &error));
  EXPECT_NE(error.find("shorter"), std::string::npos) << error;
  DepthImageView short_step = view<float>("32FC1", {1.0f, 1.0f}, &bytes);
  short_step.step_bytes = 7;
  EXPECT_FALSE(converter().convert(short_step, kFx, &d, &error));
  EXPECT_FALSE(converter().convert(view<float>("32FC1", {1.0f}, &bytes), 0.0, &d, &error));
  EXPECT_NE(error.find("fx"), std::string::npos) << error;
  DepthImageView empty;
  empty.encoding = "32FC1";
  EXPECT_FALSE(converter().convert(empty, kFx, &d, &error));
  // Nothing half-filled.
  EXPECT_EQ(d.data, untouched.data);
  EXPECT_EQ(d.at<float>(0, 0), 7.0f);
}

TEST(DepthToDisparity, BaselineOutsideItsRangeIsInvalid) {
  DepthConversionConfig config;
  EXPECT_TRUE(validateDepthConversionConfig(config).empty());
  for (double b : {0.0, -0.05, 10.5, std::nan("")}) {
    config.baseline_m = b;
    ASSERT_EQ(validateDepthConversionConfig(config).size(), 1u) << b;
    EXPECT_NE(validateDepthConversionConfig(config)[0].find("depth_baseline_m"), std::string::npos);
  }
}
