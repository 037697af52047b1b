// Fuzz target: what ROS delivers for one frame — a DisparityImage, an Image and a CameraInfo
// with fuzzed fields — through toStereoFrame() (the node's conversion) into one
// Mapper::integrate(). Input layout (ByteReader: a short input reads as zeros):
//   byte 0  flags  bit 0 raw float K and P (else plausible values scaled from bytes)
//                  bit 1 P unset (K only)
//                  bit 2 raw float f, T, min/max disparity, delta_d (else plausible)
//                  bit 3 disparity big-endian
//                  bit 4 one size or step field replaced by a raw 32-bit value (byte 1 picks it)
//                  bit 5 colour encoding from byte 2 (else rgb8)
//                  bit 6 CameraInfo width / height from bytes (else the disparity's or 0)
//                  bit 7 raw float disparities (else one byte per pixel)
//   then the fields in the order read below, then the disparity pixels, then the pose.
// A message set is converted or refused with a reason; a converted frame has the camera's size;
// a frame the map rejects leaves it as it was; the mesh stays finite with valid indices.
#include <sensor_msgs/image_encodings.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

#include "FuzzSupport.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/ros/MessageConversions.h"

using namespace stereo_fusion;
namespace enc = sensor_msgs::image_encodings;

namespace {

constexpr uint32_t kWidth = 16;
constexpr uint32_t kHeight = 12;

Mapper& mapper() {
  static const std::unique_ptr<Mapper> m = [] {
    MapperConfig c;
    c.num_threads = 1;
    c.min_coherent_pixel_share = 0.0;  // fuzzed disparities reach the lookup and fusion
    c.histogram_min_points = 0;
    return std::make_unique<Mapper>(c);
  }();
  m->reset();
  return *m;
}

uint32_t u32(fuzz::ByteReader& in) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(in.u8()) << (8 * i);
  return v;
}

std::string encodingFor(uint8_t b) {
  static const std::string kEncodings[] = {enc::RGB8,  enc::BGR8,   enc::RGBA8, enc::BGRA8,
                                           enc::MONO8, enc::MONO16, "yuv422",   ""};
  return kEncodings[b % 8];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::ByteReader in(data, size);
  const uint8_t flags = in.u8();
  const uint8_t broken_field = in.u8();
  const uint8_t encoding = in.u8();

  sensor_msgs::CameraInfo info;
  double fx, fy, cx, cy;
  if (flags & 1) {
    fx = in.f32(), fy = in.f32(), cx = in.f32(), cy = in.f32();
  } else {
    fx = in.scaled(5, 60), fy = fx * in.scaled(0.5, 1.5), cx = in.scaled(-4, 20);
    cy = in.scaled(-4, 16);
  }
  info.K = {fx, 0, cx, 0, fy, cy, 0, 0, 1};
  if (!(flags & 2)) info.P = {fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0};
  info.width = (flags & 64) ? in.u8() : kWidth;
  info.height = (flags & 64) ? in.u8() : kHeight;

  stereo_msgs::DisparityImage disparity;
  if (flags & 4) {
    disparity.f = in.f32(), disparity.T = in.f32();
    disparity.min_disparity = in.f32(), disparity.max_disparity = in.f32();
    disparity.delta_d = in.f32();
  } else {
    disparity.f = static_cast<float>(fx) * static_cast<float>(in.scaled(0.995, 1.005));
    disparity.T = static_cast<float>(in.scaled(0.01, 0.5));
    disparity.min_disparity = static_cast<float>(in.scaled(0, 4));
    disparity.max_disparity = static_cast<float>(in.scaled(0, 64));
    disparity.delta_d = static_cast<float>(in.scaled(0, 1));
  }
  sensor_msgs::Image& d = disparity.image;
  d.encoding = enc::TYPE_32FC1;
  d.width = kWidth, d.height = kHeight, d.step = kWidth * 4;
  d.is_bigendian = (flags & 8) ? 1 : 0;
  d.data.resize(size_t{d.step} * d.height);
  for (uint32_t k = 0; k < kWidth * kHeight; ++k) {
    float v = (flags & 128) ? in.f32() : in.u8() / 4.0f;
    uint8_t* p = d.data.data() + 4 * k;
    std::memcpy(p, &v, 4);
    if (d.is_bigendian) std::reverse(p, p + 4);
  }

  sensor_msgs::Image image;
  image.encoding = (flags & 32) ? encodingFor(encoding) : enc::RGB8;
  image.width = kWidth, image.height = kHeight, image.step = kWidth * 3;
  image.data.assign(size_t{image.step} * image.height, in.u8());
  if (flags & 16) {
    // One size or step field with any 32-bit value, the data left as it is.
    const uint32_t raw = u32(in);
    switch (broken_field % 6) {
      case 0: d.width = raw; break;
      case 1: d.height = raw; break;
      case 2: d.step = raw; break;
      case 3: image.width = raw; break;
      case 4: image.height = raw; break;
      default: image.step = raw; break;
    }
  }

  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  T_world_camera.translation() = Eigen::Vector3d(in.scaled(-2, 2), in.scaled(-2, 2), 0);

  StereoFrame frame;
  std::string error;
  if (!toStereoFrame(disparity, image, info, T_world_camera, &frame, &error)) {
    fuzz::require(!error.empty());
    return 0;
  }
  fuzz::require(frame.camera.valid());
  fuzz::require(frame.disparity_px.cols == frame.camera.width() &&
                frame.disparity_px.rows == frame.camera.height());
  fuzz::require(frame.color.empty() || (frame.color.cols == frame.disparity_px.cols &&
                                        frame.color.rows == frame.disparity_px.rows));

  Mapper& map = mapper();
  const IntegrationResult result = map.integrate(frame);
  if (!result.accepted) {
    fuzz::require(!result.error.empty());
    fuzz::require(map.tsdf().blockCount() == 0);
  }
  fuzz::checkMesh(map.extractMesh());
  return 0;
}
