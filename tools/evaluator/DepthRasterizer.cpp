#include "evaluator/DepthRasterizer.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace stereo_fusion::eval {
namespace {

/// A clipped triangle corner projected to the image: pixel coordinates and 1/z.
struct ScreenVertex {
  double u, v, inv_z;
};

/// Draws one triangle into the z-buffer, keeping the smaller depth at every pixel centre it
/// covers (edges included, so neighbouring triangles leave no gaps).
void drawTriangle(const ScreenVertex& a, const ScreenVertex& b, const ScreenVertex& c,
                  cv::Mat* depth) {
  const double area = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
  if (!(std::abs(area) > 1e-12)) return;  // edge-on or degenerate: covers no pixel centre
  const double u_min = std::max(0.0, std::ceil(std::min({a.u, b.u, c.u})));
  const double u_max = std::min(depth->cols - 1.0, std::floor(std::max({a.u, b.u, c.u})));
  const double v_min = std::max(0.0, std::ceil(std::min({a.v, b.v, c.v})));
  const double v_max = std::min(depth->rows - 1.0, std::floor(std::max({a.v, b.v, c.v})));
  if (u_min > u_max || v_min > v_max) return;
  const double inv_area = 1.0 / area;
  // Signed edge functions, normalised to barycentric weights; a small negative slack keeps
  // pixel centres exactly on a shared edge from being missed by both triangles to rounding.
  constexpr double kSlack = -1e-9;
  for (int v = static_cast<int>(v_min); v <= static_cast<int>(v_max); ++v) {
    float* row = depth->ptr<float>(v);
    for (int u = static_cast<int>(u_min); u <= static_cast<int>(u_max); ++u) {
      const double wa = ((b.u - u) * (c.v - v) - (b.v - v) * (c.u - u)) * inv_area;
      const double wb = ((c.u - u) * (a.v - v) - (c.v - v) * (a.u - u)) * inv_area;
      const double wc = 1.0 - wa - wb;
      if (wa < kSlack || wb < kSlack || wc < kSlack) continue;
      const double inv_z = wa * a.inv_z + wb * b.inv_z + wc * c.inv_z;
      if (!(inv_z > 0.0)) continue;
      const float z = static_cast<float>(1.0 / inv_z);
      if (row[u] == 0.0f || z < row[u]) row[u] = z;
    }
  }
}

}  // namespace

cv::Mat rasterizeDepth(const TriangleMesh& mesh, const StereoCamera& camera,
                       const Eigen::Isometry3d& T_world_camera, double near_m) {
  cv::Mat depth(camera.height(), camera.width(), CV_32FC1, cv::Scalar(0));
  if (!camera.valid()) return depth;
  const Eigen::Isometry3d T_camera_world = T_world_camera.inverse();
  std::vector<Eigen::Vector3d> vertices_camera(mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    vertices_camera[i] = T_camera_world * mesh.positions[i].cast<double>();
  }
  const auto project = [&](const Eigen::Vector3d& p) {
    return ScreenVertex{camera.fx() * p.x() / p.z() + camera.cx(),
                        camera.fy() * p.y() / p.z() + camera.cy(), 1.0 / p.z()};
  };

  const size_t vertex_count = vertices_camera.size();
  for (const auto& tri : mesh.triangles) {
    if (tri[0] >= vertex_count || tri[1] >= vertex_count || tri[2] >= vertex_count) continue;
    const std::array<Eigen::Vector3d, 3> corners = {
        vertices_camera[tri[0]], vertices_camera[tri[1]], vertices_camera[tri[2]]};
    // Clip against the plane z = near (Sutherland–Hodgman on one plane): a triangle crossing
    // it becomes a triangle or a quad; projecting unclipped corners behind the camera would
    // flip them across the image.
    std::array<Eigen::Vector3d, 4> clipped;
    int n = 0;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = corners[k];
      const Eigen::Vector3d& q = corners[(k + 1) % 3];
      const bool p_in = p.z() >= near_m, q_in = q.z() >= near_m;
      if (p_in) clipped[n++] = p;
      if (p_in != q_in) {
        const double t = (near_m - p.z()) / (q.z() - p.z());
        clipped[n++] = p + t * (q - p);
      }
    }
    if (n < 3) continue;
    const ScreenVertex s0 = project(clipped[0]);
    for (int k = 1; k + 1 < n; ++k) {
      drawTriangle(s0, project(clipped[k]), project(clipped[k + 1]), &depth);
    }
  }
  return depth;
}

}  // namespace stereo_fusion::eval
