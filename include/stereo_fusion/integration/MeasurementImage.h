#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/integration/LevelSelection.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// What the measurement image reads (from the parameter table: StageConfigs).
struct MeasurementConfig {
  double min_depth_m = MapperConfig{}.min_depth_m;
  double max_depth_m = MapperConfig{}.max_depth_m;
  bool use_color = MapperConfig{}.use_color;
  LevelConfig levels;  ///< where the frame's measurements switch levels
};

/// What one pixel of a frame tells the fuser, converted once per frame so that the voxels of
/// all blocks that project onto a pixel share the work:
///  - depth: z = f·b/d (eq. 3.1), or NaN where there is no usable measurement (d ≤ 0 or not
///    finite, or z outside [min_depth_m, max_depth_m]). A valid depth is never NaN, so
///    "is NaN" is the whole validity test.
///  - colour: R | G << 8 | B << 16 as one 32-bit word (grey repeated in all three), so that
///    one gather fetches the colours of eight pixels.
///
/// Buffers are kept across frames: rebuilding for a frame of the same size allocates nothing.
class MeasurementImage {
 public:
  /// Fills the image from `disparity_px` (CV_32FC1, any row stride) with z = fb_px_m / d, the
  /// very float expression of the fuser, so depths are bit-identical to a per-voxel division;
  /// and from `color` (CV_8UC3 RGB or CV_8UC1, same size) unless it is empty, in which case
  /// colours() must not be used. Rows are converted in parallel on `pool`.
  void build(const cv::Mat& disparity_px, const cv::Mat& color, float fb_px_m, float min_depth_m,
             float max_depth_m, ThreadPool* pool);
  /// The frame's measurements as the pipeline uses them: f·b of its camera, the configured
  /// depth range, colours only if `config.use_color`. Built once per frame (the Mapper's first
  /// step), read by the lookup (depths) and by fusion (depths and colours).
  void build(const StereoFrame& frame, const MeasurementConfig& config, ThreadPool* pool);

  int width() const { return width_; }
  int height() const { return height_; }
  /// The frame's level switch depths (levelThresholdsFor() of its camera), set by the
  /// frame-level build(); the thesis' 2 m / 4 m before any.
  const LevelThresholds& levels() const { return levels_; }
  /// Row-major depths, width() per row, no padding.
  const float* depths() const { return depth_m_.data(); }
  /// Makes the pixels where `reject` (CV_8UC1, this size) is non-zero unusable (depth NaN);
  /// returns how many of them had a depth (OutlierRejection). Rows in parallel on `pool`.
  uint64_t invalidate(const cv::Mat& reject, ThreadPool* pool = nullptr);
  /// Row-major packed colours, width() per row, no padding.
  const uint32_t* colours() const { return rgb_.data(); }

  /// The bytes R, G, B of a packed colour word.
  static void unpack(uint32_t rgb, uint8_t out[3]) {
    out[0] = static_cast<uint8_t>(rgb);
    out[1] = static_cast<uint8_t>(rgb >> 8);
    out[2] = static_cast<uint8_t>(rgb >> 16);
  }

 private:
  std::vector<float> depth_m_;
  LevelThresholds levels_;
  std::vector<uint32_t> rgb_;
  int width_ = 0;
  int height_ = 0;
};

}  // namespace stereo_fusion
