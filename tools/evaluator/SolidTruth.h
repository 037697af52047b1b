#pragma once
// The signed distance to a ground-truth mesh read as solids: how far a point lies from the true
// surface, and on which side of it.

#include <Eigen/Core>
#include <vector>

#include "evaluator/TriangleBvh.h"
#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion::eval {

/// Signed distance to a mesh whose triangles are wound counter-clockwise seen from free space,
/// so their normals point out of the solid (as the simulator's gt_mesh.ply: a room's walls and
/// every box are solid). The magnitude is the exact distance to the nearest triangle; the sign is
/// negative when the point lies behind that triangle, (p − q)·n < 0 with q the nearest point and
/// n the triangle's winding normal.
///
/// The sign comes from the winding rather than the PLY's vertex normals: the winding is what the
/// simulator guarantees per triangle, vertex normals are averages over corners. Where solids
/// overlap or touch (a box on the floor, a sofa's back on its seat) an inner face can be the
/// nearest and read its own side as free: the rule assumes the solids' surfaces do not meet.
class SolidTruth {
 public:
  explicit SolidTruth(const TriangleMesh& mesh);

  /// Metres, positive in free space, negative inside a solid; +inf for a mesh without triangles.
  double signedDistance(const Eigen::Vector3d& p) const;

  /// The BVH behind it, for unsigned queries.
  const TriangleBvh& bvh() const { return bvh_; }

 private:
  TriangleBvh bvh_;
  std::vector<Eigen::Vector3d> normals_;  ///< per mesh triangle, (b − a) × (c − a), not unit
};

}  // namespace stereo_fusion::eval
