// CompressedImageDecoding: the `compressed` and `compressedDepth` transports' messages, made as
// image_transport_plugins' publishers make them, decoded back.
#include <gtest/gtest.h>
#include <sensor_msgs/image_encodings.h>

#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "stereo_fusion/ros/CompressedImageDecoding.h"

using namespace stereo_fusion;

namespace {

/// A 6×4 RGB image whose every pixel and channel differ.
cv::Mat rgbPattern() {
  cv::Mat rgb(4, 6, CV_8UC3);
  for (int v = 0; v < 4; ++v)
    for (int u = 0; u < 6; ++u)
      rgb.at<cv::Vec3b>(v, u) = cv::Vec3b(10 * u + 1, 40 * v + 2, 200 - 7 * u - 9 * v);
  return rgb;
}

cv::Mat asMat(const sensor_msgs::Image& image, int type) {
  return cv::Mat(image.height, image.width, type, const_cast<uint8_t*>(image.data.data()),
                 image.step);
}

sensor_msgs::CompressedImage compressed(const std::string& format, const std::string& extension,
                                        const cv::Mat& image) {
  sensor_msgs::CompressedImage c;
  c.header.stamp = ros::Time(12, 34);
  c.header.frame_id = "cam";
  c.format = format;
  EXPECT_TRUE(cv::imencode(extension, image, c.data));
  return c;
}

}  // namespace

TEST(CompressedImageDecoding, PngOfAnRgbImageComesBackInRgbOrderExactly) {
  const cv::Mat rgb = rgbPattern();
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  sensor_msgs::Image out;
  std::string error;
  ASSERT_TRUE(
      decodeCompressedImage(compressed("rgb8; png compressed bgr8", ".png", bgr), &out, &error))
      << error;
  EXPECT_EQ(out.encoding, "rgb8");
  EXPECT_EQ(out.header.stamp, ros::Time(12, 34));
  EXPECT_EQ(out.header.frame_id, "cam");
  ASSERT_EQ(out.width, 6u);
  ASSERT_EQ(out.height, 4u);
  EXPECT_EQ(cv::norm(asMat(out, CV_8UC3), rgb, cv::NORM_INF), 0.0);
  // bgr8 stays BGR.
  ASSERT_TRUE(
      decodeCompressedImage(compressed("bgr8; png compressed bgr8", ".png", bgr), &out, &error));
  EXPECT_EQ(out.encoding, "bgr8");
  EXPECT_EQ(cv::norm(asMat(out, CV_8UC3), bgr, cv::NORM_INF), 0.0);
}

TEST(CompressedImageDecoding, JpegAndMonoAndBareFormats) {
  // A flat colour survives JPEG within a few levels, in the original channel order.
  cv::Mat rgb(16, 16, CV_8UC3, cv::Scalar(200, 100, 30));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  sensor_msgs::Image out;
  std::string error;
  ASSERT_TRUE(
      decodeCompressedImage(compressed("rgb8; jpeg compressed bgr8", ".jpg", bgr), &out, &error))
      << error;
  EXPECT_EQ(out.encoding, "rgb8");
  EXPECT_LE(cv::norm(asMat(out, CV_8UC3), rgb, cv::NORM_INF), 4.0);
  // mono8.
  cv::Mat grey(3, 5, CV_8UC1);
  for (int i = 0; i < 15; ++i) grey.data[i] = static_cast<uint8_t>(17 * i);
  ASSERT_TRUE(
      decodeCompressedImage(compressed("mono8; png compressed mono8", ".png", grey), &out, &error));
  EXPECT_EQ(out.encoding, "mono8");
  EXPECT_EQ(cv::norm(asMat(out, CV_8UC1), grey, cv::NORM_INF), 0.0);
  // Older publishers name the codec only: colour is bgr8, one channel mono8.
  ASSERT_TRUE(decodeCompressedImage(compressed("png", ".png", bgr), &out, &error));
  EXPECT_EQ(out.encoding, "bgr8");
  EXPECT_EQ(cv::norm(asMat(out, CV_8UC3), bgr, cv::NORM_INF), 0.0);
  ASSERT_TRUE(decodeCompressedImage(compressed("jpeg", ".png", grey), &out, &error));
  EXPECT_EQ(out.encoding, "mono8");
}

TEST(CompressedImageDecoding, BytesThatDoNotDecodeOrDisagreeAreRefused) {
  sensor_msgs::CompressedImage garbage;
  garbage.format = "rgb8; jpeg compressed bgr8";
  garbage.data = {1, 2, 3, 4, 5};
  sensor_msgs::Image out;
  std::string error;
  EXPECT_FALSE(decodeCompressedImage(garbage, &out, &error));
  EXPECT_NE(error.find("does not decode"), std::string::npos) << error;
  garbage.data.clear();
  EXPECT_FALSE(decodeCompressedImage(garbage, &out, &error));
  // A grey PNG that claims rgb8.
  const cv::Mat grey(3, 5, CV_8UC1, cv::Scalar(9));
  EXPECT_FALSE(
      decodeCompressedImage(compressed("rgb8; png compressed bgr8", ".png", grey), &out, &error));
  EXPECT_NE(error.find("channels"), std::string::npos) << error;
}

namespace {

/// compressedDepth's data: {int32 format, float a, float b} then the PNG.
sensor_msgs::CompressedImage compressedDepth(const std::string& format, float a, float b,
                                             const cv::Mat& png16) {
  sensor_msgs::CompressedImage c;
  c.format = format;
  std::vector<uint8_t> png;
  EXPECT_TRUE(cv::imencode(".png", png16, png));
  c.data.resize(12);
  const int32_t kind = 0;  // INV_DEPTH
  std::memcpy(c.data.data(), &kind, 4);
  std::memcpy(c.data.data() + 4, &a, 4);
  std::memcpy(c.data.data() + 8, &b, 4);
  c.data.insert(c.data.end(), png.begin(), png.end());
  return c;
}

}  // namespace

TEST(CompressedImageDecoding, CompressedDepthMillimetresAndQuantisedInverseMetres) {
  cv::Mat mm(1, 3, CV_16UC1);
  mm.at<uint16_t>(0, 0) = 1250;
  mm.at<uint16_t>(0, 1) = 0;
  mm.at<uint16_t>(0, 2) = 65535;
  sensor_msgs::Image out;
  std::string error;
  ASSERT_TRUE(
      decodeCompressedDepth(compressedDepth("16UC1; compressedDepth png", 0, 0, mm), &out, &error))
      << error;
  EXPECT_EQ(out.encoding, "16UC1");
  EXPECT_EQ(cv::norm(asMat(out, CV_16UC1), mm, cv::NORM_INF), 0.0);
  // 32FC1: z = a / (q − b); a = 10000, b = −0.5: q = 5000 → 10000/5000.5 m, q = 2500 →
  // 10000/2500.5 m, q = 0 → no measurement (NaN).
  cv::Mat q(1, 3, CV_16UC1);
  q.at<uint16_t>(0, 0) = 5000;
  q.at<uint16_t>(0, 1) = 2500;
  q.at<uint16_t>(0, 2) = 0;
  ASSERT_TRUE(decodeCompressedDepth(
      compressedDepth("32FC1; compressedDepth png", 10000.0f, -0.5f, q), &out, &error))
      << error;
  EXPECT_EQ(out.encoding, "32FC1");
  const cv::Mat z = asMat(out, CV_32FC1);
  EXPECT_FLOAT_EQ(z.at<float>(0, 0), 10000.0f / 5000.5f);
  EXPECT_FLOAT_EQ(z.at<float>(0, 1), 10000.0f / 2500.5f);
  EXPECT_TRUE(std::isnan(z.at<float>(0, 2)));
  // RVL, unknown formats, a missing image: refused.
  EXPECT_FALSE(
      decodeCompressedDepth(compressedDepth("16UC1; compressedDepth rvl", 0, 0, mm), &out, &error));
  EXPECT_NE(error.find("RVL"), std::string::npos) << error;
  EXPECT_FALSE(
      decodeCompressedDepth(compressedDepth("rgb8; compressedDepth png", 0, 0, mm), &out, &error));
  sensor_msgs::CompressedImage header_only =
      compressedDepth("16UC1; compressedDepth png", 0, 0, mm);
  header_only.data.resize(12);
  EXPECT_FALSE(decodeCompressedDepth(header_only, &out, &error));
}
