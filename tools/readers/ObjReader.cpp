#include "readers/ObjReader.h"

#include <filesystem>
#include <fstream>
#include <sstream>

namespace stereo_fusion {

namespace fs = std::filesystem;

namespace {

bool readMtl(const fs::path& path, std::vector<ObjMaterial>* materials, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path.string() + ": cannot open";
    return false;
  }
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "newmtl") {
      materials->push_back({});
      ls >> materials->back().name;
    } else if (tag == "map_Kd" && !materials->empty()) {
      std::string file;
      ls >> file;
      materials->back().diffuse_map = (path.parent_path() / file).string();
    }
  }
  return true;
}

/// "a", "a/b", "a//c" or "a/b/c" → 0-based indices (negative OBJ indices count from the end).
bool parseCorner(const std::string& text, const ObjMesh& m, int* v, int* vt, int* vn) {
  int idx[3] = {0, 0, 0};
  size_t start = 0;
  for (int k = 0; k < 3 && start <= text.size(); ++k) {
    const size_t slash = text.find('/', start);
    const std::string part = text.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    if (!part.empty()) {
      try {
        size_t used = 0;
        idx[k] = std::stoi(part, &used);
        if (used != part.size()) return false;
      } catch (...) {
        return false;
      }
    }
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  auto resolve = [](int i, size_t n) { return i > 0 ? i - 1 : i < 0 ? static_cast<int>(n) + i : -1; };
  *v = resolve(idx[0], m.positions.size());
  *vt = resolve(idx[1], m.uvs.size());
  *vn = resolve(idx[2], m.normals.size());
  return *v >= 0 && *v < static_cast<int>(m.positions.size()) && *vt < static_cast<int>(m.uvs.size()) &&
         *vn < static_cast<int>(m.normals.size()) && (idx[1] == 0 || *vt >= 0) && (idx[2] == 0 || *vn >= 0);
}

}  // namespace

bool readObj(const std::string& path, ObjMesh* mesh, std::string* error) {
  *mesh = ObjMesh{};
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  std::string line;
  int current_material = -1, current_object = -1;
  bool any_color = false;
  for (size_t line_no = 1; std::getline(in, line); ++line_no) {
    const std::string where = path + ":" + std::to_string(line_no);
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag) || tag[0] == '#') continue;
    if (tag == "v") {
      std::vector<float> values;
      float x;
      while (ls >> x) values.push_back(x);
      if (values.size() != 3 && values.size() != 6) {
        *error = where + ": a vertex needs 3 or 6 numbers";
        return false;
      }
      mesh->positions.emplace_back(values[0], values[1], values[2]);
      if (values.size() == 6) any_color = true;
      mesh->colors.emplace_back(values.size() == 6 ? Eigen::Vector3f(values[3], values[4], values[5])
                                                   : Eigen::Vector3f::Ones());
    } else if (tag == "vt") {
      float u, v;
      if (!(ls >> u >> v)) {
        *error = where + ": malformed vt";
        return false;
      }
      mesh->uvs.emplace_back(u, v);
    } else if (tag == "vn") {
      float x, y, z;
      if (!(ls >> x >> y >> z)) {
        *error = where + ": malformed vn";
        return false;
      }
      mesh->normals.emplace_back(x, y, z);
    } else if (tag == "f") {
      std::vector<std::array<int, 3>> corners;
      std::string c;
      while (ls >> c) {
        std::array<int, 3> idx;
        if (!parseCorner(c, *mesh, &idx[0], &idx[1], &idx[2])) {
          *error = where + ": bad face corner '" + c + "'";
          return false;
        }
        corners.push_back(idx);
      }
      if (corners.size() < 3) {
        *error = where + ": a face needs 3 corners";
        return false;
      }
      for (size_t k = 1; k + 1 < corners.size(); ++k) {
        ObjFace face;
        const std::array<int, 3>* tri[3] = {&corners[0], &corners[k], &corners[k + 1]};
        for (int j = 0; j < 3; ++j) {
          face.v[j] = (*tri[j])[0];
          face.vt[j] = (*tri[j])[1];
          face.vn[j] = (*tri[j])[2];
        }
        face.material = current_material;
        face.object = current_object;
        mesh->faces.push_back(face);
      }
    } else if (tag == "mtllib") {
      std::string file;
      ls >> file;
      if (!readMtl(fs::path(path).parent_path() / file, &mesh->materials, error)) return false;
    } else if (tag == "usemtl") {
      std::string name;
      ls >> name;
      current_material = -1;
      for (size_t i = 0; i < mesh->materials.size(); ++i)
        if (mesh->materials[i].name == name) current_material = static_cast<int>(i);
      if (current_material < 0) {
        *error = where + ": unknown material '" + name + "'";
        return false;
      }
    } else if (tag == "o" || tag == "g") {
      std::string name;
      ls >> name;
      mesh->objects.push_back(name);
      current_object = static_cast<int>(mesh->objects.size()) - 1;
    }
  }
  if (!any_color) mesh->colors.clear();
  return true;
}

}  // namespace stereo_fusion
