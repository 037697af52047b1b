#include "readers/ObjReader.h"

#include <tiny_obj_loader.h>

#include <filesystem>

namespace stereo_fusion {

namespace fs = std::filesystem;

namespace {

/// tinyobjloader's 0-based index (-1 = absent) checked against `count` elements; false if it
/// points past them (tinyobjloader only warns about that, and for triangles copies it as is).
bool checkIndex(int index, size_t count, bool required) {
  if (index < 0) return !required;
  return static_cast<size_t>(index) < count;
}

}  // namespace

bool readObj(const std::string& path, ObjMesh* mesh, std::string* error) {
  *mesh = ObjMesh{};
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  // Colours only when every vertex has r g b (otherwise tinyobjloader would fill in white).
  config.vertex_color = false;
  config.mtl_search_path = fs::path(path).parent_path().string();
  tinyobj::ObjReader reader;
  const bool parsed = reader.ParseFromFile(path, config);
  // Its warnings are what this reader used to refuse (an unknown material, a face with fewer
  // than three corners, indices out of bounds): they stay errors.
  if (!parsed || !reader.Warning().empty()) {
    std::string why = reader.Error() + reader.Warning();
    while (!why.empty() && (why.back() == '\n' || why.back() == '.')) why.pop_back();
    *error = path + ": " + (why.empty() ? "cannot read" : why);
    return false;
  }
  const tinyobj::attrib_t& attrib = reader.GetAttrib();
  const size_t vertex_count = attrib.vertices.size() / 3;
  mesh->positions.reserve(vertex_count);
  for (size_t i = 0; i < vertex_count; ++i)
    mesh->positions.emplace_back(attrib.vertices[3 * i], attrib.vertices[3 * i + 1],
                                 attrib.vertices[3 * i + 2]);
  if (attrib.colors.size() == attrib.vertices.size()) {
    mesh->colors.reserve(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i)
      mesh->colors.emplace_back(attrib.colors[3 * i], attrib.colors[3 * i + 1],
                                attrib.colors[3 * i + 2]);
  }
  for (size_t i = 0; i + 1 < attrib.texcoords.size(); i += 2)
    mesh->uvs.emplace_back(attrib.texcoords[i], attrib.texcoords[i + 1]);
  for (size_t i = 0; i + 2 < attrib.normals.size(); i += 3)
    mesh->normals.emplace_back(attrib.normals[i], attrib.normals[i + 1], attrib.normals[i + 2]);

  const fs::path folder = fs::path(path).parent_path();
  for (const tinyobj::material_t& material : reader.GetMaterials()) {
    ObjMaterial m;
    m.name = material.name;
    if (!material.diffuse_texname.empty())
      m.diffuse_map = (folder / material.diffuse_texname).string();
    mesh->materials.push_back(std::move(m));
  }

  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    int object = -1;
    // tinyobjloader starts a new shape at each `usemtl` too: one object, several shapes.
    if (!shape.name.empty()) {
      if (mesh->objects.empty() || mesh->objects.back() != shape.name)
        mesh->objects.push_back(shape.name);
      object = static_cast<int>(mesh->objects.size()) - 1;
    }
    const tinyobj::mesh_t& m = shape.mesh;
    size_t corner = 0;
    for (size_t f = 0; f < m.num_face_vertices.size(); ++f) {
      const size_t corners = m.num_face_vertices[f];
      if (corners != 3 || corner + 3 > m.indices.size()) {
        *error = path + ": face " + std::to_string(f) + " of object '" + shape.name +
                 "' was not triangulated";
        return false;
      }
      ObjFace face;
      for (int k = 0; k < 3; ++k) {
        const tinyobj::index_t& index = m.indices[corner + k];
        if (!checkIndex(index.vertex_index, mesh->positions.size(), true) ||
            !checkIndex(index.texcoord_index, mesh->uvs.size(), false) ||
            !checkIndex(index.normal_index, mesh->normals.size(), false)) {
          *error = path + ": face " + std::to_string(f) + " of object '" + shape.name +
                   "' has an index out of bounds (v " + std::to_string(index.vertex_index + 1) +
                   " of " + std::to_string(mesh->positions.size()) + ")";
          return false;
        }
        face.v[k] = index.vertex_index;
        face.vt[k] = index.texcoord_index;
        face.vn[k] = index.normal_index;
      }
      corner += 3;
      const int material = f < m.material_ids.size() ? m.material_ids[f] : -1;
      face.material =
          material >= 0 && static_cast<size_t>(material) < mesh->materials.size() ? material : -1;
      face.object = object;
      mesh->faces.push_back(face);
    }
  }
  return true;
}

}  // namespace stereo_fusion
