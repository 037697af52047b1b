#pragma once
#include <string>

#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion {

/// Writes `mesh` as binary little-endian PLY: vertex x y z nx ny nz (float) red green blue
/// (uchar), face vertex_indices (uchar count, int indices). Loads in MeshLab, Blender,
/// Open3D and PCL. Returns false with a message naming the file on I/O failure.
bool writePly(const std::string& path, const TriangleMesh& mesh, std::string* error);

/// writePly() through a temporary beside `path` (writeThroughTemporary(), WriteTarget.h): the
/// file is written whole or not at all; `what` names it in messages ("mesh").
bool writePlyWhole(const std::string& path, const std::string& what, const TriangleMesh& mesh,
                   std::string* error);

}  // namespace stereo_fusion
