// computeVertexNormals() (declared in SubMesh.h): the mesher's last step per submesh, and
// used by the tools for meshes of their own.
#include <Eigen/Geometry>

#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion {

void computeVertexNormals(TriangleMesh* mesh) {
  mesh->normals.assign(mesh->positions.size(), Eigen::Vector3f::Zero());
  for (const auto& t : mesh->triangles) {
    const Eigen::Vector3f n = (mesh->positions[t[1]] - mesh->positions[t[0]])
                                  .cross(mesh->positions[t[2]] - mesh->positions[t[0]]);
    for (uint32_t v : t) mesh->normals[v] += n;
  }
  for (Eigen::Vector3f& n : mesh->normals) {
    const float len = n.norm();
    n = len > 0.0f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::UnitZ();
  }
}

}  // namespace stereo_fusion
