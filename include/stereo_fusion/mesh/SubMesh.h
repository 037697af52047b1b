#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "stereo_fusion/map/BlockKey.h"

namespace stereo_fusion {

/// An indexed triangle mesh with per-vertex normals and colours, in the world frame.
struct TriangleMesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;        ///< unit, pointing to free space (negative SDF)
  std::vector<std::array<uint8_t, 3>> colors;  ///< RGB
  std::vector<std::array<uint32_t, 3>> triangles;

  bool empty() const { return triangles.empty(); }
  void clear() {
    positions.clear();
    normals.clear();
    colors.clear();
    triangles.clear();
  }
};

/// Sets `mesh->normals` to the area-weighted face normals of each vertex (the triangles'
/// winding: towards negative SDF for the mesher's triangles); +z where no face touches a vertex.
void computeVertexNormals(TriangleMesh* mesh);

/// The triangles one block contributes to the global mesh: its own cells plus the seams it
/// owns towards +x/+y/+z. Vertices on the same cell edge are shared.
struct SubMesh : TriangleMesh {
  BlockKey key;
  int level = 0;  ///< the level this block was sampled at
};

}  // namespace stereo_fusion
