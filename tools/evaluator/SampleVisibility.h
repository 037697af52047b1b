#pragma once
// Which ground-truth surface samples a sequence actually saw.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "stereo_fusion/io/FrameSource.h"

namespace stereo_fusion::eval {

/// Per-point visibility over a sequence.
struct VisibilityResult {
  std::vector<uint8_t> visible;  ///< 1 when the point was seen in at least one frame
  size_t visible_count = 0;
  size_t frames_used = 0;
  size_t frames_skipped = 0;         ///< frames that failed to load
  std::vector<std::string> skipped;  ///< reasons, first few only
};

/// A world point is visible when, in at least one frame, it lies in front of the camera,
/// projects to a pixel inside the image, and that pixel's measured depth z = f·b/d agrees with
/// the point's depth within `tolerance_m` (so occluded and unmatched points do not count).
/// Frames are loaded one at a time (FrameSource::load is never called concurrently); points are
/// tested in parallel on `num_threads` threads (0 = all cores). The result does not depend on
/// the thread count.
VisibilityResult computeVisibility(const std::vector<Eigen::Vector3d>& points_world_m,
                                   const FrameSource& frames, double tolerance_m,
                                   int num_threads = 0);

}  // namespace stereo_fusion::eval
