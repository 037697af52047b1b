#include "evaluator/SeenTriangles.h"

#include <cmath>

#include "evaluator/DepthRasterizer.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion::eval {

std::vector<uint8_t> seenTriangles(const TriangleMesh& mesh, const FrameSource& frames,
                                   double tolerance_m, int num_threads) {
  std::vector<uint8_t> seen(mesh.triangles.size(), 0);
  std::vector<Eigen::Vector3d> centroids(mesh.triangles.size(), Eigen::Vector3d::Zero());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (tri[0] >= mesh.positions.size() || tri[1] >= mesh.positions.size() ||
        tri[2] >= mesh.positions.size())
      continue;
    centroids[t] =
        (mesh.positions[tri[0]] + mesh.positions[tri[1]] + mesh.positions[tri[2]]).cast<double>() /
        3.0;
  }
  ThreadPool pool(num_threads);
  for (size_t f = 0; f < frames.size(); ++f) {
    StereoFrame frame;
    std::string error;
    if (!frames.load(f, &frame, &error) || !frame.camera.valid()) continue;
    const cv::Mat depth_m = rasterizeDepth(mesh, frame.camera, frame.T_world_camera);
    const Eigen::Isometry3d T_camera_world = frame.T_world_camera.inverse();
    pool.parallelFor(mesh.triangles.size(), 4096, [&](size_t begin, size_t end) {
      for (size_t t = begin; t < end; ++t) {
        if (seen[t]) continue;
        const Eigen::Vector3d p_camera = T_camera_world * centroids[t];
        Eigen::Vector2d uv;
        if (!frame.camera.project(p_camera, &uv) || !frame.camera.isInImage(uv)) continue;
        const int u = static_cast<int>(std::floor(uv.x() + 0.5));
        const int v = static_cast<int>(std::floor(uv.y() + 0.5));
        const float nearest_m = depth_m.at<float>(v, u);
        if (nearest_m > 0.0f && p_camera.z() <= nearest_m + tolerance_m) seen[t] = 1;
      }
    });
  }
  return seen;
}

TriangleMesh keepTriangles(const TriangleMesh& mesh, const std::vector<uint8_t>& keep) {
  TriangleMesh out;
  out.positions = mesh.positions;
  out.normals = mesh.normals;
  out.colors = mesh.colors;
  for (size_t t = 0; t < mesh.triangles.size() && t < keep.size(); ++t)
    if (keep[t]) out.triangles.push_back(mesh.triangles[t]);
  return out;
}

}  // namespace stereo_fusion::eval
