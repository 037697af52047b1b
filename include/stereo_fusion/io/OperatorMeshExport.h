#pragma once
// The fleet's operator mesh (issue 51): several robots' meshes, each welded in its own map frame,
// carried into the operator frame by their current alignments and written as one PLY.
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion {

/// One robot's welded mesh (weldSubmeshes) and T_operator_robot, its map frame in the operator
/// frame.
struct PlacedMesh {
  const TriangleMesh* mesh = nullptr;
  Eigen::Isometry3d T_operator_robot = Eigen::Isometry3d::Identity();
};

/// The meshes in order, each vertex carried as T · p and each normal as R · n in double and
/// rounded once to float (so a vertex is within half a float ulp of the exact transform of the
/// robot's float vertex), colours as they are, triangles re-indexed past the vertices of the
/// meshes before. Nothing is welded or dropped across robots: where robots overlap both
/// surfaces stay.
TriangleMesh placeMeshes(const std::vector<PlacedMesh>& meshes);

/// placeMeshes() written as binary PLY (writePly) through a temporary beside `path`; `message`
/// says what was written, or why nothing was.
bool exportOperatorMesh(const std::string& path, const std::vector<PlacedMesh>& meshes,
                        std::string* message);

}  // namespace stereo_fusion
