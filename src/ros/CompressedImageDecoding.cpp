#include "stereo_fusion/ros/CompressedImageDecoding.h"

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/image_encodings.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace stereo_fusion {

namespace enc = sensor_msgs::image_encodings;

namespace {

std::string trimmed(const std::string& s) {
  const size_t first = s.find_first_not_of(' ');
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(' ') - first + 1);
}

void toMessage(const std_msgs::Header& header, const std::string& encoding, const cv::Mat& image,
               sensor_msgs::Image* out) {
  cv_bridge::CvImage(header, encoding, image).toImageMsg(*out);
}

}  // namespace

bool decodeCompressedImage(const sensor_msgs::CompressedImage& in, sensor_msgs::Image* out,
                           std::string* error) {
  cv::Mat decoded;
  try {
    decoded = cv::imdecode(
        cv::Mat(1, static_cast<int>(in.data.size()), CV_8UC1, const_cast<uint8_t*>(in.data.data())),
        cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
    decoded.release();
  }
  if (decoded.empty()) {
    *error = "compressed image (format '" + in.format + "', " + std::to_string(in.data.size()) +
             " bytes) does not decode as JPEG or PNG";
    return false;
  }
  const size_t split = in.format.find(';');
  if (split == std::string::npos) {  // older publishers: the format names the codec only
    std::string encoding;
    if (decoded.channels() == 1)
      encoding = decoded.depth() == CV_16U ? enc::MONO16 : enc::MONO8;
    else if (decoded.channels() == 3 && decoded.depth() == CV_8U)
      encoding = enc::BGR8;
    else if (decoded.channels() == 4 && decoded.depth() == CV_8U)
      encoding = enc::BGRA8;
    else {
      *error = "compressed image of format '" + in.format + "' decodes to an unsupported type";
      return false;
    }
    toMessage(in.header, encoding, decoded, out);
    return true;
  }
  const std::string encoding = trimmed(in.format.substr(0, split));
  const bool compressed_bgr = in.format.find("compressed bgr", split) != std::string::npos;
  if (enc::isColor(encoding) && decoded.channels() >= 3) {
    // imdecode gives the bytes in the order they were compressed in: back to the original
    // channel order, as image_transport_plugins' subscriber does.
    const bool rgb = encoding == enc::RGB8 || encoding == enc::RGB16;
    const bool rgba = encoding == enc::RGBA8 || encoding == enc::RGBA16;
    const bool bgra = encoding == enc::BGRA8 || encoding == enc::BGRA16;
    const bool bgr = encoding == enc::BGR8 || encoding == enc::BGR16;
    if (decoded.channels() == 4) cv::cvtColor(decoded, decoded, cv::COLOR_BGRA2BGR);
    if (compressed_bgr) {
      if (rgb) cv::cvtColor(decoded, decoded, cv::COLOR_BGR2RGB);
      if (rgba) cv::cvtColor(decoded, decoded, cv::COLOR_BGR2RGBA);
      if (bgra) cv::cvtColor(decoded, decoded, cv::COLOR_BGR2BGRA);
    } else {  // compressed in RGB order
      if (bgr) cv::cvtColor(decoded, decoded, cv::COLOR_RGB2BGR);
      if (bgra) cv::cvtColor(decoded, decoded, cv::COLOR_RGB2BGRA);
      if (rgba) cv::cvtColor(decoded, decoded, cv::COLOR_BGR2RGBA);
    }
  }
  int channels = 0;
  try {
    channels = enc::numChannels(encoding);
  } catch (const std::exception&) {
    *error = "compressed image of unknown encoding '" + encoding + "' (format '" + in.format + "')";
    return false;
  }
  if (decoded.channels() != channels) {
    *error = "compressed image says '" + encoding + "' (" + std::to_string(channels) +
             " channels) but decodes to " + std::to_string(decoded.channels()) + " channels";
    return false;
  }
  toMessage(in.header, encoding, decoded, out);
  return true;
}

bool decodeCompressedDepth(const sensor_msgs::CompressedImage& in, sensor_msgs::Image* out,
                           std::string* error) {
  const size_t split = in.format.find(';');
  const std::string encoding = trimmed(in.format.substr(0, split));
  const std::string codec = split == std::string::npos ? "" : in.format.substr(split + 1);
  if (codec.find("compressedDepth") == std::string::npos ||
      (encoding != enc::TYPE_16UC1 && encoding != enc::TYPE_32FC1)) {
    *error = "compressedDepth format '" + in.format +
             "' is not '16UC1; compressedDepth png' or '32FC1; compressedDepth png'";
    return false;
  }
  if (codec.find("rvl") != std::string::npos) {
    *error = "compressedDepth with RVL coding is not supported (publish it with format png)";
    return false;
  }
  constexpr size_t kHeaderBytes = 12;  // int32 format, float depthParam[2]
  if (in.data.size() <= kHeaderBytes) {
    *error = "compressedDepth data of " + std::to_string(in.data.size()) +
             " bytes holds no image after its 12-byte header";
    return false;
  }
  float quant_a, quant_b;
  std::memcpy(&quant_a, in.data.data() + 4, 4);
  std::memcpy(&quant_b, in.data.data() + 8, 4);
  cv::Mat png;
  try {
    png = cv::imdecode(cv::Mat(1, static_cast<int>(in.data.size() - kHeaderBytes), CV_8UC1,
                               const_cast<uint8_t*>(in.data.data() + kHeaderBytes)),
                       cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
    png.release();
  }
  if (png.empty() || png.type() != CV_16UC1) {
    *error = "compressedDepth data does not decode as a 16-bit one-channel PNG";
    return false;
  }
  if (encoding == enc::TYPE_16UC1) {
    toMessage(in.header, encoding, png, out);
    return true;
  }
  if (!std::isfinite(quant_a) || !std::isfinite(quant_b)) {
    *error = "compressedDepth 32FC1 quantisation parameters are not finite";
    return false;
  }
  cv::Mat depth(png.rows, png.cols, CV_32FC1);
  for (int v = 0; v < png.rows; ++v) {
    const uint16_t* q = png.ptr<uint16_t>(v);
    float* z = depth.ptr<float>(v);
    for (int u = 0; u < png.cols; ++u)
      z[u] = q[u] != 0 ? quant_a / (static_cast<float>(q[u]) - quant_b)
                       : std::numeric_limits<float>::quiet_NaN();
  }
  toMessage(in.header, encoding, depth, out);
  return true;
}

}  // namespace stereo_fusion
