#pragma once
// Exact Euclidean distance from a point to a triangle (a solid, closed triangle: its face, its
// edges and its corners), robust to degenerate (zero-area) triangles.

#include <Eigen/Core>

namespace stereo_fusion::eval {

/// The closest point of triangle (a, b, c) to `p`. Degenerate triangles (collinear or
/// coincident corners) are treated as the segments between their corners.
Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Squared distance from `p` to triangle (a, b, c), in m².
inline double squaredDistanceToTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                        const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return (closestPointOnTriangle(p, a, b, c) - p).squaredNorm();
}

/// The closest point of segment [a, b] to `p` (a when the segment has zero length).
Eigen::Vector3d closestPointOnSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                      const Eigen::Vector3d& b);

}  // namespace stereo_fusion::eval
