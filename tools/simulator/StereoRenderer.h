#pragma once
// Renders rectified stereo pairs of an analytic scene and the left disparity, exact, noisy or
// computed by OpenCV's semi-global matcher from the rendered pair.

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>

#include "readers/DatasetReader.h"  // SgbmParams: the same knobs as the reader's SGBM
#include "simulator/AnalyticScene.h"
#include "stereo_fusion/camera/StereoCamera.h"

namespace stereo_fusion::sim {

/// How the left disparity of a simulated frame is made.
enum class DisparityMode {
  kExact,  ///< d = f·b / z from the exact depth
  kNoisy,  ///< exact + Gaussian noise + uniform outliers (DisparityNoiseParams)
  kSgbm,   ///< cv::StereoSGBM on the rendered pair (realistic holes, edges, smoothing)
};

/// "exact" | "noisy" | "sgbm" → mode; std::nullopt for anything else.
std::optional<DisparityMode> parseDisparityMode(const std::string& name);
/// Mode → its name as parseDisparityMode() accepts it.
const char* disparityModeName(DisparityMode mode);

/// Noise model of DisparityMode::kNoisy, applied to valid (d > 0) pixels only.
struct DisparityNoiseParams {
  double sigma_px = 0.3;           ///< σ of the Gaussian error of inliers
  double outlier_fraction = 0.01;  ///< share of valid pixels replaced by an outlier
  double outlier_min_px = 1.0;     ///< outliers are uniform in [outlier_min_px, outlier_max_px)
  double outlier_max_px = 128.0;
};

/// Matcher errors added on top of any disparity mode, as real matchers make them: Gaussian
/// noise per pixel and frame, and mismatches tied to the surface — in a window of
/// `mismatch_views` consecutive frames, a share of the scene's surface patches (cubes of
/// `mismatch_patch_m` in the world) where the matcher errs by the same 1–3 px, towards or away
/// from the camera, in every view of the window (it errs on the same texture seen alike, so the
/// errors agree across neighbouring views as true surfaces do). Each patch's windows start at
/// their own frame; `mismatch_views` 0 ties a patch's error to every view.
struct MatcherErrorParams {
  double sigma_px = 0.0;
  double mismatch_fraction = 0.0;
  double mismatch_patch_m = 0.05;
  double mismatch_min_px = 1.0, mismatch_max_px = 3.0;
  int mismatch_views = 5;
  bool any() const { return sigma_px > 0.0 || mismatch_fraction > 0.0; }
};

/// The mismatch of the surface patch holding `p_world` in frame `frame_index` (0 for most
/// patches): a function of the patch, the patch's window of frames and `scene_seed` only.
double surfaceMismatchPx(const Eigen::Vector3d& p_world, uint64_t frame_index,
                         const MatcherErrorParams& params, uint64_t scene_seed);

/// Adds MatcherErrorParams' errors to the valid (d > 0) pixels of `disparity_px`; a pixel's
/// surface point comes from the exact `depth_m` of the view at T_world_left (no mismatch where
/// it hit nothing). Pixels whose value is no longer positive become invalid (0).
void addMatcherErrors(cv::Mat* disparity_px, const cv::Mat& depth_m, const StereoCamera& camera,
                      const Eigen::Isometry3d& T_world_left, uint64_t frame_index,
                      const MatcherErrorParams& params, uint64_t scene_seed);

/// Everything that decides a rendered frame besides the scene, camera and pose.
struct StereoRenderConfig {
  DisparityMode mode = DisparityMode::kSgbm;
  DisparityNoiseParams noise;
  MatcherErrorParams matcher;  ///< on top of `mode`'s disparity
  SgbmParams sgbm;
  uint32_t seed = 0;  ///< with the frame index, seeds the noise of each frame
};

/// One simulated stereo frame (left camera).
struct StereoView {
  cv::Mat left_rgb;      ///< CV_8UC3, RGB
  cv::Mat right_rgb;     ///< CV_8UC3, RGB, rectified right camera
  cv::Mat depth_m;       ///< CV_32FC1, exact left depth z, 0 where nothing is hit
  cv::Mat disparity_px;  ///< CV_32FC1, left disparity, 0 = invalid
};

/// Pose of the right rectified camera: the left one moved by +baseline along its own x axis.
Eigen::Isometry3d rightCameraPose(const Eigen::Isometry3d& T_world_left, double baseline_m);

/// Renders the left colour + exact depth and the right colour of the pair at T_world_left.
void renderStereoPair(const AnalyticScene& scene, const StereoCamera& camera,
                      const Eigen::Isometry3d& T_world_left, cv::Mat* left_rgb, cv::Mat* right_rgb,
                      cv::Mat* depth_m);

/// Exact disparity with Gaussian noise and outliers (see DisparityNoiseParams). Deterministic
/// in `seed` with any standard library (own Box–Muller on mt19937_64). Pixels whose noisy
/// value is not positive become invalid (0).
cv::Mat addDisparityNoise(const cv::Mat& exact_disparity_px, const DisparityNoiseParams& noise,
                          uint64_t seed);

/// Semi-global matching on a rectified RGB pair: CV_32FC1 disparity in pixels, 0 = invalid
/// (including the left strip where the search range leaves the right image).
class SgbmMatcher {
 public:
  /// Matcher set up like DatasetReader's (grey input, P1 = 8·block², P2 = 32·block², 3-way mode).
  explicit SgbmMatcher(const SgbmParams& params);
  /// Disparity of the left image of a rectified CV_8UC3 RGB pair.
  cv::Mat compute(const cv::Mat& left_rgb, const cv::Mat& right_rgb);

 private:
  cv::Ptr<cv::StereoSGBM> sgbm_;
  cv::Mat left_grey_, right_grey_, fixed_point_;  // reused buffers
};

/// Renders frames of one scene with one camera; frame `k`'s noise is seeded by (seed, k), so a
/// frame does not depend on which frames were rendered before it.
class StereoRenderer {
 public:
  /// `scene` must outlive the renderer.
  StereoRenderer(const AnalyticScene& scene, const StereoCamera& camera,
                 const StereoRenderConfig& config);
  /// Frame `frame_index` seen by the left camera at T_world_left.
  StereoView render(const Eigen::Isometry3d& T_world_left, uint64_t frame_index);

 private:
  const AnalyticScene& scene_;
  StereoCamera camera_;
  StereoRenderConfig config_;
  std::optional<SgbmMatcher> sgbm_;
};

}  // namespace stereo_fusion::sim
