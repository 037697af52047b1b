#pragma once
// Small software z-buffer: the depth image a camera would see of a triangle mesh.

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "stereo_fusion/camera/StereoCamera.h"
#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion::eval {

/// Renders the depth (z in the camera frame, metres) of the nearest surface of `mesh` at every
/// pixel centre of `camera` placed at `T_world_camera`: CV_32FC1, 0 where no triangle covers
/// the pixel. Both sides of a triangle are drawn (a reconstruction's winding is not trusted).
/// Triangles are clipped at `near_m` in front of the camera, and depth is interpolated
/// perspective-correctly (linear in 1/z on the image). Pixel (u, v) has its centre at the
/// continuous coordinate (u, v), as in StereoCamera::project.
cv::Mat rasterizeDepth(const TriangleMesh& mesh, const StereoCamera& camera,
                       const Eigen::Isometry3d& T_world_camera, double near_m = 0.01);

}  // namespace stereo_fusion::eval
