#pragma once
#include <cstdint>

#include <opencv2/core/mat.hpp>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/integration/MeasurementImage.h"

namespace stereo_fusion {

/// What outlier rejection reads (from the parameter table: StageConfigs).
struct OutlierConfig {
  int speckle_max_area_px = MapperConfig{}.speckle_max_area_px;
  double speckle_max_diff_px = MapperConfig{}.speckle_max_diff_px;
  int edge_reject_radius_px = MapperConfig{}.edge_reject_radius_px;
  double edge_reject_jump_px = MapperConfig{}.edge_reject_jump_px;
};

/// Pixels a frame's outlier rejection made unusable, by rule.
struct OutlierRejectionStats {
  uint64_t speckle_pixels = 0;  ///< in blobs of at most speckle_max_area_px disparities
  uint64_t edge_pixels =
      0;  ///< nearer than a neighbour within edge_reject_radius_px by > edge_reject_jump_px
};

/// Measurement-level outlier rejection, before the lookup (stage 0): pixels the stereo geometry
/// or their neighbourhood says are unreliable lose their depth in the MeasurementImage, so the
/// lookup, fusion and carving all ignore them.
///
///  - Speckles: a connected blob (4-neighbours whose disparities differ by at most
///    speckle_max_diff_px) of at most speckle_max_area_px pixels, isolated mismatches that
///    become floaters. OpenCV's filterSpeckles, the matcher's own post-filter, on disparities
///    in 1/16 px; a source that ran it already (SGBM, stereo_image_proc) loses nothing more.
///  - Fattened borders: block matching lends a foreground object's disparity to the background
///    pixels next to it, a band of surface floating in front of the background. A pixel with a
///    usable neighbour within edge_reject_radius_px (square window) whose disparity is smaller
///    by more than edge_reject_jump_px lies on the near side of a depth edge and is dropped; the
///    far side is kept. A plane's disparity changes by at most b/D px per px (D: the plane's
///    distance from the camera centre; 0.33 px for a road 1.65 m below a 0.54 m baseline), so
///    the default jump of 1 px over a radius of 1 px keeps every plane farther from the camera
///    than the baseline (radius · b / jump); an object at most 2 · radius pixels wide is
///    dropped whole.
///
/// Buffers are kept across frames. The result depends only on the images and the config.
class OutlierRejection {
 public:
  /// Applies both rules (each off when its size parameter is 0) to the usable pixels of
  /// `measurements`, built from `disparity_px` (CV_32FC1, same size); the edge rule's per-pixel
  /// passes in rows on `pool` when given (the same result).
  OutlierRejectionStats apply(const cv::Mat& disparity_px, const OutlierConfig& config,
                              MeasurementImage* measurements, ThreadPool* pool = nullptr);

 private:
  cv::Mat usable_;       // CV_8U: 255 where the measurement image holds a depth (speckles)
  cv::Mat reject_;       // CV_8U: 255 where a rule rejects
  cv::Mat fixed_point_;  // CV_16S disparities in 1/16 px for filterSpeckles
  cv::Mat speckle_buffer_;
  cv::Mat masked_;    // disparities, +inf where unusable
  cv::Mat farthest_;  // smallest usable disparity in each pixel's window
};

}  // namespace stereo_fusion
