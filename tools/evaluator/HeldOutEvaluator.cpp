#include "evaluator/HeldOutEvaluator.h"

#include <cmath>
#include <memory>
#include <mutex>

#include <opencv2/imgcodecs.hpp>

#include "evaluator/DepthRasterizer.h"
#include "evaluator/DistanceStats.h"
#include "evaluator/ResidualHistogram.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion::eval {
namespace {

constexpr size_t kMaxReasonsKept = 5;

/// Compares a rendered depth image with a frame's measurement, pixel by pixel.
HeldOutCounts compareFrame(const cv::Mat& mesh_depth, const StereoFrame& frame,
                           const HeldOutOptions& options, ResidualHistogram* histogram) {
  HeldOutCounts counts;
  for (int v = 0; v < mesh_depth.rows; ++v) {
    const float* rendered = mesh_depth.ptr<float>(v);
    const float* disparity = frame.disparity_px.ptr<float>(v);
    for (int u = 0; u < mesh_depth.cols; ++u) {
      const double measured = frame.camera.depthFromDisparity(disparity[u]);  // +inf if invalid
      const bool has_measurement =
          measured >= options.min_depth_m && measured <= options.max_depth_m;
      const bool has_mesh = rendered[u] > 0.0f;
      counts.measured_pixels += has_measurement;
      counts.mesh_pixels += has_mesh;
      if (!has_measurement || !has_mesh) continue;
      const double residual = rendered[u] - measured;
      ++counts.overlap_pixels;
      counts.abs_residual_sum_m += std::abs(residual);
      counts.agreeing_pixels += std::abs(residual) <= options.tolerance_m;
      counts.floating_pixels += residual < -options.tolerance_m;
      counts.over_10cm_pixels += std::abs(residual) > kGrossErrorM;
      histogram->add(std::abs(residual));
    }
  }
  return counts;
}

bool writeDepth(const std::string& path, const cv::Mat& depth_m) {
  try {
    return cv::imwrite(path, depth_m);
  } catch (const cv::Exception&) {  // OpenCV throws for some unwritable targets
    return false;
  }
}

double ratio(uint64_t numerator, uint64_t denominator) {
  return denominator == 0 ? NAN : static_cast<double>(numerator) / static_cast<double>(denominator);
}

}  // namespace

std::string renderedDepthPath(const std::string& folder, size_t frame_index) {
  return folder + "/" + std::to_string(frame_index) + ".tiff";
}

HeldOutResult evaluateHeldOut(const TriangleMesh& mesh, const FrameSource& frames,
                              const std::vector<size_t>& held_out, const HeldOutOptions& options) {
  struct FrameOutcome {
    bool ok = false;
    std::string error;
    HeldOutCounts counts;
  };
  std::vector<FrameOutcome> outcomes(held_out.size());
  ResidualHistogram histogram;
  std::mutex histogram_mutex;
  std::mutex load_mutex;

  ThreadPool pool(options.num_threads);
  pool.parallelFor(held_out.size(), 1, [&](size_t begin, size_t end) {
    // One histogram per chunk, merged once: 320 KB, too big to keep one per frame.
    auto local = std::make_unique<ResidualHistogram>();
    for (size_t i = begin; i < end; ++i) {
      FrameOutcome& outcome = outcomes[i];
      StereoFrame frame;
      if (held_out[i] >= frames.size()) {
        outcome.error = "frame " + std::to_string(held_out[i]) + " does not exist";
        continue;
      }
      {
        // Loading is serialised (a source such as a rosbag reader may keep state); the
        // rendering and comparison, the expensive part, still run in parallel.
        std::lock_guard<std::mutex> lock(load_mutex);
        if (!frames.load(held_out[i], &frame, &outcome.error)) continue;
      }
      if (!frame.camera.valid() || frame.disparity_px.type() != CV_32FC1 ||
          frame.disparity_px.cols != frame.camera.width() ||
          frame.disparity_px.rows != frame.camera.height()) {
        outcome.error =
            "frame " + std::to_string(held_out[i]) + ": disparity does not match camera";
        continue;
      }
      const cv::Mat rendered = rasterizeDepth(mesh, frame.camera, frame.T_world_camera);
      if (!options.rendered_depth_folder.empty()) {
        const std::string path = renderedDepthPath(options.rendered_depth_folder, held_out[i]);
        if (!writeDepth(path, rendered)) {
          outcome.error = "frame " + std::to_string(held_out[i]) + ": cannot write " + path;
          continue;
        }
      }
      outcome.counts = compareFrame(rendered, frame, options, local.get());
      outcome.ok = true;
    }
    std::lock_guard<std::mutex> lock(histogram_mutex);
    histogram.merge(*local);
  });

  HeldOutResult result;
  for (size_t i = 0; i < held_out.size(); ++i) {
    const FrameOutcome& outcome = outcomes[i];
    if (!outcome.ok) {
      ++result.frames_skipped;
      if (result.skipped.size() < kMaxReasonsKept) result.skipped.push_back(outcome.error);
      continue;
    }
    result.frames_evaluated.push_back(held_out[i]);
    result.per_frame.push_back(outcome.counts);
    HeldOutCounts& t = result.total;
    t.measured_pixels += outcome.counts.measured_pixels;
    t.mesh_pixels += outcome.counts.mesh_pixels;
    t.overlap_pixels += outcome.counts.overlap_pixels;
    t.agreeing_pixels += outcome.counts.agreeing_pixels;
    t.floating_pixels += outcome.counts.floating_pixels;
    t.over_10cm_pixels += outcome.counts.over_10cm_pixels;
    t.abs_residual_sum_m += outcome.counts.abs_residual_sum_m;  // in frame order: deterministic
  }
  const HeldOutCounts& t = result.total;
  result.median_abs_residual_m = histogram.quantile(0.5);
  result.p90_abs_residual_m = histogram.quantile(0.9);
  result.p99_abs_residual_m = histogram.quantile(0.99);
  result.mean_abs_residual_m =
      t.overlap_pixels == 0 ? NAN : t.abs_residual_sum_m / static_cast<double>(t.overlap_pixels);
  result.floating_share = ratio(t.floating_pixels, t.overlap_pixels);
  result.share_over_10cm = ratio(t.over_10cm_pixels, t.overlap_pixels);
  result.completeness = ratio(t.agreeing_pixels, t.measured_pixels);
  return result;
}

}  // namespace stereo_fusion::eval
