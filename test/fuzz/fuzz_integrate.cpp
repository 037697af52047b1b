// Fuzz target: Mapper::integrate() on fuzzed 32x24 disparity images, intrinsics and poses.
// Input layout (ByteReader: a short input reads as zeros):
//   byte 0  flags  bit 0 raw float intrinsics (else scaled from bytes)
//                  bit 1 raw float pose matrices (else scaled axis-angle, translation and
//                        a power of ten for the translation)
//                  bit 2 colour image present, bit 3 grey (else RGB)
//                  bits 4-5 mapper configuration (kConfigs)
//                  bit 6 raw float disparities (else one byte per pixel, see disparityFromByte)
//   byte 1  frames − 1 (mod 3)
//   intrinsics fx fy cx cy baseline, per frame a pose, then the disparity image (shared)
// Every frame must be fused or rejected with a reason; a rejected frame leaves the map as it
// was; the incremental mesh stays finite with valid indices.
#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>

#include "FuzzSupport.h"
#include "stereo_fusion/Mapper.h"

using namespace stereo_fusion;

namespace {

constexpr int kWidth = 32;
constexpr int kHeight = 24;
constexpr int kConfigCount = 5;

MapperConfig configFor(int variant) {
  MapperConfig c;
  c.num_threads = 1;  // deterministic coverage; threads are TSan's job (scripts/check.sh)
  // Fuzzed disparities are mostly incoherent: variant 0 exercises that rejection, the others
  // let such frames through to the lookup and fusion.
  if (variant != 0) c.min_coherent_pixel_share = 0.0;
  switch (variant) {
    case 1:  // smaller voxels, Algorithm 1, every point counts, constant weight
      c.voxel_size_m = 0.01;
      c.lookup_mode = LookupMode::kNaive;
      c.histogram_min_points = 0;
      c.weight_mode = WeightMode::kConstant;
      break;
    case 2:  // odd region size, depth-aware weights, no colour
      c.voxel_size_m = 0.02;
      c.lookup_region_px = 5;
      c.histogram_min_points = 1;
      c.weight_mode = WeightMode::kDepthAware;
      c.use_color = false;
      break;
    case 3:  // the extremes of the ranges: widest band, all depths. Voxels are not the finest:
             // maps cost time, not coverage (0.002 m took a minute per input under ASan).
      c.voxel_size_m = 0.04;
      c.truncation_vox = 8;
      c.min_depth_m = 0.0;
      c.max_depth_m = 1000.0;
      c.level_mode = LevelMode::kDepth;
      c.levels.scale2_min_depth_m = 1000.0;
      c.levels.scale4_min_depth_m = 1000.0;
      c.histogram_min_points = 0;
      break;
    case 4:  // levels from the camera's depth error, a very noisy source: coarse levels from near
      c.disparity_noise_px = 5.0;
      break;
    default: break;
  }
  return c;
}

/// One mapper per configuration, reset per input (building thread pools per input is slow).
Mapper& mapperFor(int variant) {
  static std::unique_ptr<Mapper> mappers[kConfigCount];
  if (!mappers[variant]) mappers[variant] = std::make_unique<Mapper>(configFor(variant));
  mappers[variant]->reset();
  return *mappers[variant];
}

/// 0 = no match, 1..250 = value / 4 px, then the values a broken matcher may send.
float disparityFromByte(uint8_t b) {
  switch (b) {
    case 251: return NAN;
    case 252: return INFINITY;
    case 253: return -INFINITY;
    case 254: return -1.0f;
    case 255: return 1e-30f;  // a positive disparity with an absurd depth
    default: return b / 4.0f;
  }
}

Eigen::Isometry3d readPose(fuzz::ByteReader& in, bool raw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (raw) {  // any 3x4 matrix: validation must refuse what is not a rigid transform
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) T.matrix()(r, c) = in.f32();
    return T;
  }
  const Eigen::Vector3d axis_angle(in.scaled(-M_PI, M_PI), in.scaled(-M_PI, M_PI),
                                   in.scaled(-M_PI, M_PI));
  if (axis_angle.norm() > 0)
    T.linear() = Eigen::AngleAxisd(axis_angle.norm(), axis_angle.normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(in.scaled(-2, 2), in.scaled(-2, 2), in.scaled(-2, 2));
  // Up to 2e8 m: past the map's range (±2.1e7 m at 2 cm voxels), and everything up to its edge,
  // where block keys near 2^28 and float voxel offsets are tested.
  T.translation() *= std::pow(10.0, in.u8() % 9);
  return T;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::ByteReader in(data, size);
  const uint8_t flags = in.u8();
  const int frames = 1 + in.u8() % 3;
  Mapper& mapper = mapperFor((flags >> 4) & 3);

  double fx, fy, cx, cy, baseline;
  if (flags & 1) {
    fx = in.f32(), fy = in.f32(), cx = in.f32(), cy = in.f32(), baseline = in.f32();
  } else {
    fx = in.scaled(5, 500), fy = in.scaled(5, 500), cx = in.scaled(-8, 40), cy = in.scaled(-8, 32);
    baseline = in.scaled(0.01, 0.5);
  }
  StereoFrame frame;
  if (auto camera = StereoCamera::create(kWidth, kHeight, fx, fy, cx, cy, baseline))
    frame.camera = *camera;
  std::vector<Eigen::Isometry3d> poses;
  for (int f = 0; f < frames; ++f) poses.push_back(readPose(in, flags & 2));

  frame.disparity_px.create(kHeight, kWidth, CV_32FC1);
  for (int v = 0; v < kHeight; ++v)
    for (int u = 0; u < kWidth; ++u)
      frame.disparity_px.at<float>(v, u) = (flags & 64) ? in.f32() : disparityFromByte(in.u8());
  if (flags & 4) {
    frame.color.create(kHeight, kWidth, (flags & 8) ? CV_8UC1 : CV_8UC3);
    const uint8_t seed = in.u8();
    for (size_t i = 0; i < frame.color.total() * frame.color.channels(); ++i)
      frame.color.data[i] = static_cast<uint8_t>(i * 37 + seed);
  }

  for (const Eigen::Isometry3d& pose : poses) {
    frame.T_world_camera = pose;
    const size_t blocks_before = mapper.tsdf().blockCount();
    const size_t triangles_before = mapper.mesh().triangleCount();
    const IntegrationResult result = mapper.integrate(frame);
    if (!result.accepted) {
      fuzz::require(!result.error.empty());
      fuzz::require(mapper.tsdf().blockCount() == blocks_before);
      fuzz::require(mapper.mesh().triangleCount() == triangles_before);
    }
    for (const BlockKey& key : result.mesh.changed) {
      const auto it = mapper.mesh().submeshes().find(key);
      fuzz::require(it != mapper.mesh().submeshes().end());
      fuzz::checkMesh(it->second);
    }
  }
  fuzz::checkMesh(mapper.extractMesh());
  return 0;
}
