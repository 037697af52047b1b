#include "texture_compare/ObjRenderable.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace stereo_fusion::texcmp {

bool objToRenderable(const ObjMesh& obj,
                     std::unordered_map<BlockKey, SubMesh, BlockKeyHash>* meshes,
                     std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* patches,
                     std::string* error) {
  meshes->clear();
  patches->clear();
  std::vector<cv::Mat> atlases(obj.materials.size());
  for (size_t m = 0; m < obj.materials.size(); ++m) {
    if (obj.materials[m].diffuse_map.empty()) continue;
    const cv::Mat bgr = cv::imread(obj.materials[m].diffuse_map, cv::IMREAD_COLOR);
    if (bgr.empty()) {
      *error = obj.materials[m].diffuse_map + ": cannot read the texture";
      return false;
    }
    cv::cvtColor(bgr, atlases[m], cv::COLOR_BGR2RGB);
  }
  std::map<std::pair<int, int>, int> groups;  // (object, material) → group index
  for (const ObjFace& f : obj.faces) {
    const auto [it, inserted] =
        groups.try_emplace({f.object, f.material}, static_cast<int>(groups.size()));
    const BlockKey key{it->second, 0, 0};
    SubMesh& mesh = (*meshes)[key];
    mesh.key = key;
    const bool textured = f.material >= 0 && !atlases[f.material].empty() && f.vt[0] >= 0 &&
                          f.vt[1] >= 0 && f.vt[2] >= 0;
    TexturePatch* patch = nullptr;
    if (textured) {
      patch = &(*patches)[key];
      if (patch->image_rgb.empty()) patch->image_rgb = atlases[f.material];  // shared, not copied
    }
    const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    for (int k = 0; k < 3; ++k) {
      mesh.positions.push_back(obj.positions[f.v[k]]);
      mesh.normals.push_back(f.vn[k] >= 0 ? obj.normals[f.vn[k]] : Eigen::Vector3f::Zero());
      const Eigen::Vector3f c = obj.colors.empty() ? Eigen::Vector3f::Ones() : obj.colors[f.v[k]];
      mesh.colors.push_back(
          {static_cast<uint8_t>(std::lround(std::clamp(c.x(), 0.0f, 1.0f) * 255)),
           static_cast<uint8_t>(std::lround(std::clamp(c.y(), 0.0f, 1.0f) * 255)),
           static_cast<uint8_t>(std::lround(std::clamp(c.z(), 0.0f, 1.0f) * 255))});
      if (patch) patch->uvs.emplace_back(obj.uvs[f.vt[k]].x(), 1.0f - obj.uvs[f.vt[k]].y());
    }
    mesh.triangles.push_back({base, base + 1, base + 2});
  }
  // A group mixing faces with and without UVs cannot be drawn from one patch: use its colours.
  for (auto it = patches->begin(); it != patches->end();) {
    if (it->second.uvs.size() != meshes->at(it->first).positions.size())
      it = patches->erase(it);
    else
      ++it;
  }
  return true;
}

}  // namespace stereo_fusion::texcmp
