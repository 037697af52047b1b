#include "evaluator/SolidTruth.h"

#include <Eigen/Geometry>  // cross()

namespace stereo_fusion::eval {

SolidTruth::SolidTruth(const TriangleMesh& mesh) : bvh_(mesh) {
  normals_.reserve(mesh.triangles.size());
  const size_t n = mesh.positions.size();
  for (const auto& t : mesh.triangles) {
    if (t[0] >= n || t[1] >= n || t[2] >= n) {  // ignored by the BVH as well
      normals_.emplace_back(Eigen::Vector3d::Zero());
      continue;
    }
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>(),
                          b = mesh.positions[t[1]].cast<double>(),
                          c = mesh.positions[t[2]].cast<double>();
    normals_.push_back((b - a).cross(c - a));
  }
}

double SolidTruth::signedDistance(const Eigen::Vector3d& p) const {
  NearestSurfacePoint nearest;
  if (!bvh_.nearest(p, &nearest)) return INFINITY;
  const bool behind = (p - nearest.point_m).dot(normals_[nearest.triangle]) < 0.0;
  return behind ? -nearest.distance_m : nearest.distance_m;
}

}  // namespace stereo_fusion::eval
