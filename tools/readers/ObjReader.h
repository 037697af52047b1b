#pragma once
// Wavefront OBJ + MTL through tinyobjloader (Debian's libtinyobjloader-dev), into the arrays the
// tools and the round-trip tests of ObjWriter use.

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace stereo_fusion {

/// One triangle of an OBJ file; indices are 0-based, -1 where the face gave none.
struct ObjFace {
  std::array<int, 3> v{{-1, -1, -1}};
  std::array<int, 3> vt{{-1, -1, -1}};
  std::array<int, 3> vn{{-1, -1, -1}};
  int material = -1;  ///< index into ObjMesh::materials, -1 = none
  int object = -1;    ///< index into ObjMesh::objects (`o` / `g` names), -1 = none
};

/// A material of the MTL file.
struct ObjMaterial {
  std::string name;
  std::string
      diffuse_map;  ///< map_Kd resolved against the OBJ's folder (where its MTL is); empty = none
};

/// The content of an OBJ file. Polygons are split into triangles (tinyobjloader: a quad along its
/// shorter diagonal).
struct ObjMesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f>
      colors;  ///< per position, from `v x y z r g b`; empty unless all have one
  std::vector<Eigen::Vector2f> uvs;  ///< `vt` as written (OBJ convention: v up)
  std::vector<Eigen::Vector3f> normals;
  std::vector<ObjFace> faces;
  std::vector<ObjMaterial> materials;
  std::vector<std::string> objects;
};

/// Reads `path` and the MTL libraries it names (looked up in the OBJ's folder). False with a
/// message naming the file on I/O errors, indices out of range, faces with fewer than three
/// corners or unknown materials (tinyobjloader's warnings are taken as errors). Numbers it cannot
/// parse read as 0, as tinyobjloader reads them.
bool readObj(const std::string& path, ObjMesh* mesh, std::string* error);

}  // namespace stereo_fusion
