#pragma once
#include <string>

#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion {

/// Writes `mesh` as binary little-endian PLY: vertex x y z nx ny nz (float) red green blue
/// (uchar), face vertex_indices (uchar count, int indices). Loads in MeshLab, Blender,
/// Open3D and PCL. Returns false with a message naming the file on I/O failure.
bool writePly(const std::string& path, const TriangleMesh& mesh, std::string* error);

}  // namespace stereo_fusion
