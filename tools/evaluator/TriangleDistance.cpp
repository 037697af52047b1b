#include "evaluator/TriangleDistance.h"

#include <Eigen/Geometry>
#include <algorithm>

namespace stereo_fusion::eval {

Eigen::Vector3d closestPointOnSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                      const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double length2 = ab.squaredNorm();
  if (!(length2 > 0.0)) return a;
  const double t = std::clamp((p - a).dot(ab) / length2, 0.0, 1.0);
  return a + t * ab;
}

Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a;
  const Eigen::Vector3d normal = ab.cross(ac);
  const double normal2 = normal.squaredNorm();
  // Relative threshold: a sliver whose normal is lost in rounding has no usable plane, but its
  // edges still describe its points exactly.
  const bool degenerate =
      !(normal2 > 1e-24 * ab.squaredNorm() * ac.squaredNorm()) || !(normal2 > 0.0);

  if (!degenerate) {
    // Barycentric coordinates of p's projection onto the plane, from the signed areas of the
    // sub-triangles it forms with each edge.
    const Eigen::Vector3d ap = p - a, bp = p - b, cp = p - c;
    const double wa = (c - b).cross(bp).dot(normal);    // opposite corner a
    const double wb = ac.cross(cp).dot(normal) * -1.0;  // opposite corner b: edge c->a
    const double wc = ab.cross(ap).dot(normal);         // opposite corner c
    if (wa >= 0.0 && wb >= 0.0 && wc >= 0.0) {
      // Inside: the projection is the closest point.
      return p - normal * (ap.dot(normal) / normal2);
    }
    // Outside: the closest point lies on an edge whose opposite coordinate is negative (the
    // projection is beyond that edge); at most two such edges.
    Eigen::Vector3d best = a;
    double best2 = INFINITY;
    const auto consider = [&](bool beyond, const Eigen::Vector3d& s, const Eigen::Vector3d& e) {
      if (!beyond) return;
      const Eigen::Vector3d q = closestPointOnSegment(p, s, e);
      const double d2 = (q - p).squaredNorm();
      if (d2 < best2) {
        best2 = d2;
        best = q;
      }
    };
    consider(wa < 0.0, b, c);
    consider(wb < 0.0, c, a);
    consider(wc < 0.0, a, b);
    return best;
  }

  Eigen::Vector3d best = closestPointOnSegment(p, a, b);
  double best2 = (best - p).squaredNorm();
  for (const auto& [s, e] : {std::pair{b, c}, std::pair{c, a}}) {
    const Eigen::Vector3d q = closestPointOnSegment(p, s, e);
    const double d2 = (q - p).squaredNorm();
    if (d2 < best2) {
      best2 = d2;
      best = q;
    }
  }
  return best;
}

}  // namespace stereo_fusion::eval
