#pragma once
// A small software z-buffer rasteriser for submesh maps: renders the vertex-coloured or the
// textured mesh into a camera, to compare both with ground-truth images.

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>
#include <unordered_map>

#include "stereo_fusion/camera/StereoCamera.h"
#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/mesh/TexturePatch.h"

namespace stereo_fusion::texcmp {

/// One rendered view.
struct RenderedView {
  cv::Mat rgb;       ///< CV_8UC3, RGB; black where nothing was drawn
  cv::Mat depth_m;   ///< CV_32FC1, camera z of the nearest surface; 0 where nothing was drawn
  cv::Mat textured;  ///< CV_8UC1, 255 where the pixel came from a texture patch
};

/// Renders `submeshes` seen from T_world_camera. Pixel centres sit at integer coordinates
/// (as in StereoCamera::project); a pixel is covered when its centre is inside a triangle.
/// Attributes are interpolated perspective-correctly (barycentrics divided by depth). With
/// `patches`, blocks that have a patch are drawn from it (bilinear sampling at the
/// interpolated UV); all others, and every block when `patches` is null, use the barycentric
/// blend of their vertex colours. Triangles with a vertex closer than 1 cm to the camera
/// plane are skipped (no clipping: held-out views do not get that close to the surface).
RenderedView renderMesh(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                        const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* patches,
                        const StereoCamera& camera, const Eigen::Isometry3d& T_world_camera);

}  // namespace stereo_fusion::texcmp
