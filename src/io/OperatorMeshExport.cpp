#include "stereo_fusion/io/OperatorMeshExport.h"

#include "stereo_fusion/io/PlyWriter.h"

namespace stereo_fusion {

TriangleMesh placeMeshes(const std::vector<PlacedMesh>& meshes) {
  TriangleMesh out;
  for (const PlacedMesh& placed : meshes) {
    if (placed.mesh == nullptr) continue;
    const TriangleMesh& mesh = *placed.mesh;
    const auto first = static_cast<uint32_t>(out.positions.size());
    const Eigen::Matrix3d rotation = placed.T_operator_robot.linear();
    for (const Eigen::Vector3f& p : mesh.positions)
      out.positions.push_back((placed.T_operator_robot * p.cast<double>()).cast<float>());
    for (const Eigen::Vector3f& n : mesh.normals)
      out.normals.push_back((rotation * n.cast<double>()).cast<float>());
    out.colors.insert(out.colors.end(), mesh.colors.begin(), mesh.colors.end());
    for (const auto& t : mesh.triangles)
      out.triangles.push_back({t[0] + first, t[1] + first, t[2] + first});
  }
  return out;
}

bool exportOperatorMesh(const std::string& path, const std::vector<PlacedMesh>& meshes,
                        std::string* message) {
  const TriangleMesh mesh = placeMeshes(meshes);
  if (!writePlyWhole(path, "mesh", mesh, message)) return false;
  *message = "wrote " + std::to_string(mesh.triangles.size()) + " triangles of " +
             std::to_string(meshes.size()) + " robots to " + path;
  return true;
}

}  // namespace stereo_fusion
