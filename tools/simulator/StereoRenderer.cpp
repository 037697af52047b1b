#include "simulator/StereoRenderer.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

namespace stereo_fusion::sim {

namespace {

/// SplitMix64 finaliser: decorrelates (seed, frame) pairs into independent RNG seeds.
uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// Uniform (0, 1) from the top 53 bits of one 64-bit word (never 0, so log() is safe).
double unit(std::mt19937_64* rng) { return (((*rng)() >> 11) + 0.5) * (1.0 / 9007199254740992.0); }

}  // namespace

std::optional<DisparityMode> parseDisparityMode(const std::string& name) {
  if (name == "exact") return DisparityMode::kExact;
  if (name == "noisy") return DisparityMode::kNoisy;
  if (name == "sgbm") return DisparityMode::kSgbm;
  return std::nullopt;
}

const char* disparityModeName(DisparityMode mode) {
  switch (mode) {
    case DisparityMode::kExact: return "exact";
    case DisparityMode::kNoisy: return "noisy";
    case DisparityMode::kSgbm: return "sgbm";
  }
  return "?";
}

Eigen::Isometry3d rightCameraPose(const Eigen::Isometry3d& T_world_left, double baseline_m) {
  return T_world_left * Eigen::Translation3d(baseline_m, 0.0, 0.0);
}

void renderStereoPair(const AnalyticScene& scene, const StereoCamera& camera,
                      const Eigen::Isometry3d& T_world_left, cv::Mat* left_rgb, cv::Mat* right_rgb,
                      cv::Mat* depth_m) {
  renderDepthAndColor(scene, camera, T_world_left, depth_m, left_rgb);
  // The right depth is a by-product of the shared ray caster; it is not part of the output.
  cv::Mat right_depth_m;
  renderDepthAndColor(scene, camera, rightCameraPose(T_world_left, camera.baseline()),
                      &right_depth_m, right_rgb);
}

cv::Mat addDisparityNoise(const cv::Mat& exact_disparity_px, const DisparityNoiseParams& noise,
                          uint64_t seed) {
  CV_Assert(exact_disparity_px.type() == CV_32FC1);
  cv::Mat out = exact_disparity_px.clone();
  std::mt19937_64 rng(mix(seed));
  // Sequential on purpose: one RNG stream in raster order is what makes it reproducible.
  for (int v = 0; v < out.rows; ++v) {
    float* row = out.ptr<float>(v);
    for (int u = 0; u < out.cols; ++u) {
      if (!(row[u] > 0.0f)) continue;
      double d;
      if (unit(&rng) < noise.outlier_fraction) {
        d = noise.outlier_min_px + (noise.outlier_max_px - noise.outlier_min_px) * unit(&rng);
      } else {
        const double gauss =
            std::sqrt(-2.0 * std::log(unit(&rng))) * std::cos(2 * M_PI * unit(&rng));
        d = row[u] + noise.sigma_px * gauss;
      }
      row[u] = d > 0.0 ? static_cast<float>(d) : 0.0f;
    }
  }
  return out;
}

double surfaceMismatchPx(const Eigen::Vector3d& p_world, uint64_t frame_index,
                         const MatcherErrorParams& params, uint64_t scene_seed) {
  if (!(params.mismatch_fraction > 0.0)) return 0.0;
  uint64_t h = mix(scene_seed ^ 0x6d69736d61746368ull);
  for (int a = 0; a < 3; ++a)
    h = mix(h ^ static_cast<uint64_t>(
                    static_cast<int64_t>(std::floor(p_world[a] / params.mismatch_patch_m))));
  if (params.mismatch_views > 0) {
    const uint64_t views = static_cast<uint64_t>(params.mismatch_views);
    h = mix(h ^ ((frame_index + h % views) / views));  // the patch's window of frames
  }
  std::mt19937_64 rng(h);
  if (!(unit(&rng) < params.mismatch_fraction)) return 0.0;
  const double size =
      params.mismatch_min_px + (params.mismatch_max_px - params.mismatch_min_px) * unit(&rng);
  return unit(&rng) < 0.5 ? -size : size;
}

void addMatcherErrors(cv::Mat* disparity_px, const cv::Mat& depth_m, const StereoCamera& camera,
                      const Eigen::Isometry3d& T_world_left, uint64_t frame_index,
                      const MatcherErrorParams& params, uint64_t scene_seed) {
  const uint64_t frame_seed = mix(scene_seed) ^ mix(frame_index + 0x3a7c);
  CV_Assert(disparity_px->type() == CV_32FC1 && depth_m.type() == CV_32FC1 &&
            disparity_px->size() == depth_m.size());
  std::mt19937_64 rng(mix(frame_seed ^ 0x6e6f697365ull));
  for (int v = 0; v < disparity_px->rows; ++v) {
    float* row = disparity_px->ptr<float>(v);
    const float* z = depth_m.ptr<float>(v);
    for (int u = 0; u < disparity_px->cols; ++u) {
      if (!(row[u] > 0.0f)) continue;
      double d = row[u];
      if (params.sigma_px > 0.0)
        d += params.sigma_px * std::sqrt(-2.0 * std::log(unit(&rng))) *
             std::cos(2 * M_PI * unit(&rng));
      if (z[u] > 0.0f)
        d += surfaceMismatchPx(T_world_left * camera.backProject(u, v, z[u]), frame_index, params,
                               scene_seed);
      row[u] = d > 0.0 ? static_cast<float>(d) : 0.0f;
    }
  }
}

SgbmMatcher::SgbmMatcher(const SgbmParams& p) {
  const int area = p.block_size * p.block_size;
  // P1/P2 as OpenCV's sample recommends for one channel; disp12MaxDiff = 1 enables the
  // left-right check, which removes most occlusion errors.
  sgbm_ = cv::StereoSGBM::create(0, p.num_disparities, p.block_size, 8 * area, 32 * area,
                                 /*disp12MaxDiff=*/1, /*preFilterCap=*/63, p.uniqueness_ratio,
                                 p.speckle_window_size, p.speckle_range,
                                 cv::StereoSGBM::MODE_SGBM_3WAY);
}

cv::Mat SgbmMatcher::compute(const cv::Mat& left_rgb, const cv::Mat& right_rgb) {
  cv::cvtColor(left_rgb, left_grey_, cv::COLOR_RGB2GRAY);
  cv::cvtColor(right_rgb, right_grey_, cv::COLOR_RGB2GRAY);
  sgbm_->compute(left_grey_, right_grey_, fixed_point_);
  // CV_16S with 4 fractional bits; invalid pixels are (minDisparity − 1)·16 < 0.
  cv::Mat disparity_px(fixed_point_.size(), CV_32FC1);
  for (int v = 0; v < fixed_point_.rows; ++v) {
    const int16_t* in = fixed_point_.ptr<int16_t>(v);
    float* out = disparity_px.ptr<float>(v);
    for (int u = 0; u < fixed_point_.cols; ++u) out[u] = in[u] > 0 ? in[u] / 16.0f : 0.0f;
  }
  return disparity_px;
}

StereoRenderer::StereoRenderer(const AnalyticScene& scene, const StereoCamera& camera,
                               const StereoRenderConfig& config)
    : scene_(scene), camera_(camera), config_(config) {
  if (config_.mode == DisparityMode::kSgbm) sgbm_.emplace(config_.sgbm);
}

StereoView StereoRenderer::render(const Eigen::Isometry3d& T_world_left, uint64_t frame_index) {
  StereoView view;
  renderStereoPair(scene_, camera_, T_world_left, &view.left_rgb, &view.right_rgb, &view.depth_m);
  switch (config_.mode) {
    case DisparityMode::kExact:
      view.disparity_px = disparityFromDepth(view.depth_m, camera_);
      break;
    case DisparityMode::kNoisy:
      view.disparity_px =
          addDisparityNoise(disparityFromDepth(view.depth_m, camera_), config_.noise,
                            mix(config_.seed) ^ mix(frame_index + 0x51ed));
      break;
    case DisparityMode::kSgbm:
      view.disparity_px = sgbm_->compute(view.left_rgb, view.right_rgb);
      break;
  }
  if (config_.matcher.any())
    addMatcherErrors(&view.disparity_px, view.depth_m, camera_, T_world_left, frame_index,
                     config_.matcher, config_.seed);
  return view;
}

}  // namespace stereo_fusion::sim
