#include "texture_compare/MeshRasterizer.h"

#include <algorithm>
#include <cmath>

namespace stereo_fusion::texcmp {

namespace {

constexpr double kNearPlaneM = 0.01;

double edge(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
}

}  // namespace

RenderedView renderMesh(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                        const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* patches,
                        const StereoCamera& camera, const Eigen::Isometry3d& T_world_camera) {
  RenderedView view;
  const int W = camera.width(), H = camera.height();
  view.rgb = cv::Mat(H, W, CV_8UC3, cv::Scalar(0, 0, 0));
  view.depth_m = cv::Mat(H, W, CV_32FC1, cv::Scalar(0));
  view.textured = cv::Mat(H, W, CV_8UC1, cv::Scalar(0));
  cv::Mat zbuffer(H, W, CV_64FC1, cv::Scalar(INFINITY));
  const Eigen::Isometry3d T_camera_world = T_world_camera.inverse();
  std::vector<Eigen::Vector3d> p_camera;
  std::vector<Eigen::Vector2d> px;
  for (const auto& [key, mesh] : submeshes) {
    const TexturePatch* patch = nullptr;
    if (patches) {
      const auto it = patches->find(key);
      if (it != patches->end() && it->second.uvs.size() == mesh.positions.size())
        patch = &it->second;
    }
    p_camera.resize(mesh.positions.size());
    px.resize(mesh.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      p_camera[v] = T_camera_world * mesh.positions[v].cast<double>();
      const double z = std::max(p_camera[v].z(), kNearPlaneM);
      px[v] = {camera.fx() * p_camera[v].x() / z + camera.cx(),
               camera.fy() * p_camera[v].y() / z + camera.cy()};
    }
    for (const auto& t : mesh.triangles) {
      const Eigen::Vector2d& a = px[t[0]];
      const Eigen::Vector2d& b = px[t[1]];
      const Eigen::Vector2d& c = px[t[2]];
      if (p_camera[t[0]].z() < kNearPlaneM || p_camera[t[1]].z() < kNearPlaneM ||
          p_camera[t[2]].z() < kNearPlaneM)
        continue;
      const double area = edge(a, b, c);
      if (std::abs(area) < 1e-12) continue;
      const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({a.x(), b.x(), c.x()}))));
      const int x1 = std::min(W - 1, static_cast<int>(std::floor(std::max({a.x(), b.x(), c.x()}))));
      const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({a.y(), b.y(), c.y()}))));
      const int y1 = std::min(H - 1, static_cast<int>(std::floor(std::max({a.y(), b.y(), c.y()}))));
      const double inv_z[3] = {1.0 / p_camera[t[0]].z(), 1.0 / p_camera[t[1]].z(),
                               1.0 / p_camera[t[2]].z()};
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          const Eigen::Vector2d p(x, y);
          // Screen-space barycentrics, sign-normalised so either winding is drawn.
          const double l0 = edge(b, c, p) / area, l1 = edge(c, a, p) / area,
                       l2 = edge(a, b, p) / area;
          if (l0 < 0 || l1 < 0 || l2 < 0) continue;
          // Perspective-correct weights: screen barycentrics / depth, renormalised.
          const double w0 = l0 * inv_z[0], w1 = l1 * inv_z[1], w2 = l2 * inv_z[2];
          const double sum = w0 + w1 + w2;
          const double z = 1.0 / sum;
          double& zb = zbuffer.at<double>(y, x);
          if (z >= zb) continue;
          zb = z;
          const double b0 = w0 / sum, b1 = w1 / sum, b2 = w2 / sum;
          Eigen::Vector3f rgb;
          if (patch) {
            const Eigen::Vector2f uv =
                (b0 * patch->uvs[t[0]].cast<double>() + b1 * patch->uvs[t[1]].cast<double>() +
                 b2 * patch->uvs[t[2]].cast<double>())
                    .cast<float>();
            rgb = sampleBilinear(patch->image_rgb, uv);
          } else {
            auto colour = [&](uint32_t v) {
              return Eigen::Vector3f(mesh.colors[v][0], mesh.colors[v][1], mesh.colors[v][2]);
            };
            rgb = static_cast<float>(b0) * colour(t[0]) + static_cast<float>(b1) * colour(t[1]) +
                  static_cast<float>(b2) * colour(t[2]);
          }
          cv::Vec3b& out = view.rgb.at<cv::Vec3b>(y, x);
          for (int k = 0; k < 3; ++k)
            out[k] = static_cast<uint8_t>(std::clamp(std::lround(rgb[k]), 0L, 255L));
          view.depth_m.at<float>(y, x) = static_cast<float>(z);
          view.textured.at<uint8_t>(y, x) = patch ? 255 : 0;
        }
      }
    }
  }
  return view;
}

}  // namespace stereo_fusion::texcmp
