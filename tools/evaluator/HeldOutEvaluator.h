#pragma once
// Evaluation without ground truth: render the mesh into frames that were NOT fused and compare
// with their measured depth.

#include <string>
#include <vector>

#include "stereo_fusion/io/FrameSource.h"
#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion::eval {

/// Parameters of the held-out comparison.
struct HeldOutOptions {
  /// Depth residual (metres) within which mesh and measurement agree.
  double tolerance_m = 0.04;
  /// Measurements outside [min_depth_m, max_depth_m] are ignored, as the fuser ignores them
  /// (defaults = the fuser's defaults in config/default.yaml): a mesh cannot be blamed for
  /// the sky or for what the fuser was told to drop.
  double min_depth_m = 0.1;
  double max_depth_m = 8.0;
  /// Frames rendered in parallel, the caller included; 0 = all cores.
  int num_threads = 0;
  /// Non-empty: an existing folder that receives each evaluated frame's rendered mesh depth as
  /// <frame index>.tiff (CV_32FC1 metres, 0 = no mesh). A frame whose file cannot be written is
  /// skipped with that reason.
  std::string rendered_depth_folder;
};

/// Pixel counts of one frame (or of all frames summed).
struct HeldOutCounts {
  uint64_t measured_pixels = 0;   ///< valid measured depth within the depth range
  uint64_t mesh_pixels = 0;       ///< covered by the rendered mesh
  uint64_t overlap_pixels = 0;    ///< both
  uint64_t agreeing_pixels = 0;   ///< both, with |residual| ≤ tolerance
  uint64_t floating_pixels = 0;   ///< both, mesh more than tolerance in front of the measurement
  uint64_t over_10cm_pixels = 0;  ///< both, |residual| > kGrossErrorM (DistanceStats.h)
  double abs_residual_sum_m = 0.0;
};

/// Scores of a mesh on held-out frames. Residual = mesh depth − measured depth (negative:
/// mesh in front of what the camera saw). Shares are fractions; NaN when undefined.
struct HeldOutResult {
  HeldOutCounts total;
  double median_abs_residual_m = NAN;  ///< over overlap pixels (0.1 mm histogram resolution)
  double p90_abs_residual_m = NAN;
  double p99_abs_residual_m = NAN;
  double mean_abs_residual_m = NAN;
  double floating_share = NAN;   ///< floating / overlap pixels
  double share_over_10cm = NAN;  ///< over_10cm / overlap pixels
  double completeness = NAN;     ///< agreeing / measured pixels
  std::vector<size_t> frames_evaluated;
  std::vector<HeldOutCounts> per_frame;  ///< parallel to frames_evaluated
  size_t frames_skipped = 0;
  std::vector<std::string> skipped;  ///< reasons, first few only
};

/// Where HeldOutOptions::rendered_depth_folder receives frame `frame_index`'s rendered depth.
std::string renderedDepthPath(const std::string& folder, size_t frame_index);

/// Renders `mesh` into every frame of `frames` listed in `held_out` (z-buffer, pose
/// T_world_camera) and compares with the frame's measured depth z = f·b/d pixel by pixel.
/// Frames that fail to load, and indices ≥ frames.size(), are skipped and counted. Frames are
/// rendered in parallel, but FrameSource::load is called by one thread at a time (sources need
/// not be thread-safe). The result does not depend on the thread count.
HeldOutResult evaluateHeldOut(const TriangleMesh& mesh, const FrameSource& frames,
                              const std::vector<size_t>& held_out, const HeldOutOptions& options);

}  // namespace stereo_fusion::eval
