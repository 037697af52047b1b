#include "evaluator/SampleVisibility.h"

#include <cmath>

#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion::eval {
namespace {
constexpr size_t kMaxReasonsKept = 5;
constexpr size_t kPointsPerChunk = 4096;
}  // namespace

VisibilityResult computeVisibility(const std::vector<Eigen::Vector3d>& points_world_m,
                                   const FrameSource& frames, double tolerance_m, int num_threads) {
  VisibilityResult result;
  result.visible.assign(points_world_m.size(), 0);
  ThreadPool pool(num_threads);
  for (size_t f = 0; f < frames.size(); ++f) {
    StereoFrame frame;
    std::string error;
    if (!frames.load(f, &frame, &error) || frame.disparity_px.type() != CV_32FC1 ||
        frame.disparity_px.cols != frame.camera.width() ||
        frame.disparity_px.rows != frame.camera.height() || !frame.camera.valid()) {
      ++result.frames_skipped;
      if (error.empty()) error = "frame " + std::to_string(f) + ": disparity does not match camera";
      if (result.skipped.size() < kMaxReasonsKept) result.skipped.push_back(error);
      continue;
    }
    ++result.frames_used;
    const Eigen::Isometry3d T_camera_world = frame.T_world_camera.inverse();
    const StereoCamera& camera = frame.camera;
    pool.parallelFor(points_world_m.size(), kPointsPerChunk, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) {
        if (result.visible[i]) continue;  // seen already: one frame is enough
        const Eigen::Vector3d p_camera = T_camera_world * points_world_m[i];
        Eigen::Vector2d uv;
        if (!camera.project(p_camera, &uv) || !camera.isInImage(uv)) continue;
        const int u = static_cast<int>(std::floor(uv.x() + 0.5));
        const int v = static_cast<int>(std::floor(uv.y() + 0.5));
        const double depth_m = camera.depthFromDisparity(frame.disparity_px.at<float>(v, u));
        if (std::isfinite(depth_m) && std::abs(depth_m - p_camera.z()) <= tolerance_m) {
          result.visible[i] = 1;
        }
      }
    });
  }
  for (const uint8_t v : result.visible) result.visible_count += v;
  return result;
}

}  // namespace stereo_fusion::eval
