#pragma once
// A small Wavefront OBJ + MTL reader: enough to read back what ObjWriter writes (and common
// triangle/polygon OBJ files), for round-trip tests and tools.

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
  std::string diffuse_map;  ///< map_Kd resolved against the MTL's folder; empty = none
};

/// The content of an OBJ file. Polygons are split into triangle fans.
struct ObjMesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> colors;  ///< per position, from `v x y z r g b`; empty if none had one
  std::vector<Eigen::Vector2f> uvs;     ///< `vt` as written (OBJ convention: v up)
  std::vector<Eigen::Vector3f> normals;
  std::vector<ObjFace> faces;
  std::vector<ObjMaterial> materials;
  std::vector<std::string> objects;
};

/// Reads `path` and the MTL libraries it names. False with a message (file and line) on I/O
/// errors, malformed numbers, indices out of range or unknown materials.
bool readObj(const std::string& path, ObjMesh* mesh, std::string* error);

}  // namespace stereo_fusion
