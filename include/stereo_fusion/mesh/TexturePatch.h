#pragma once
// Thesis §3.6 colour method B: one image patch per submesh, cut from the camera frame that
// sees the block best, with per-vertex texture coordinates relative to the patch.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

namespace stereo_fusion {

/// The texture of one submesh.
///
/// UV convention (image convention, NOT OpenGL/OBJ): u grows to the right, v grows DOWN,
/// (0, 0) is the top-left corner of the patch's top-left texel and (1, 1) the bottom-right
/// corner of its bottom-right texel, so texel (i, j) has its centre at ((i + 0.5) / cols,
/// (j + 0.5) / rows). The OBJ writer flips v.
struct TexturePatch {
  /// CV_8UC3, RGB; at most texture_max_patch_px per edge (downscaled when the crop is larger).
  cv::Mat image_rgb;
  /// One texture coordinate per vertex of the submesh, in [0, 1]².
  std::vector<Eigen::Vector2f> uvs;

  // Where the patch was cut from: kept so the UVs of a re-meshed block can be re-projected
  // into this patch after the source frame is gone.
  /// Source camera: world → camera (optical frame).
  Eigen::Isometry3d T_camera_world = Eigen::Isometry3d::Identity();
  double fx_px = 0, fy_px = 0, cx_px = 0, cy_px = 0;  ///< source camera intrinsics
  /// Source image coordinates of the crop's top-left pixel centre (integers).
  Eigen::Vector2d crop_origin_px = Eigen::Vector2d::Zero();
  /// Size of the crop in source image pixels (before any downscaling to the cap).
  Eigen::Vector2d crop_size_px = Eigen::Vector2d::Zero();

  /// View score of the source frame for this submesh (see TextureStore): stored texels per
  /// square metre of surface. Higher is better.
  double score_px2_per_m2 = 0;
  /// 1-based index of the fused frame the patch was cut from (Mapper::framesIntegrated()).
  uint64_t frame_index = 0;

  /// Bytes held by this patch (image + UVs), for the memory budget.
  size_t memoryBytes() const {
    return image_rgb.total() * image_rgb.elemSize() + uvs.size() * sizeof(Eigen::Vector2f);
  }
};

}  // namespace stereo_fusion

namespace stereo_fusion {

/// Bilinear sample of a CV_8UC3 image at `uv` in the texel-edge convention of TexturePatch
/// (texel (i, j) centred at ((i + ½)/cols, (j + ½)/rows)); clamps at the image edge. Channel
/// order as stored.
Eigen::Vector3f sampleBilinear(const cv::Mat& image, const Eigen::Vector2f& uv);

}  // namespace stereo_fusion
