#include "stereo_fusion/io/ObjWriter.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace stereo_fusion {

namespace fs = std::filesystem;

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

}  // namespace

bool writeTexturedObj(const std::string& obj_path,
                      const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                      const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>& patches,
                      const ObjExportOptions& options, ObjExportInfo* info, std::string* error) {
  *info = ObjExportInfo{};
  const fs::path obj(obj_path);
  if (obj.extension() != ".obj") {
    *error = obj_path + ": the textured mesh must be written to a .obj file";
    return false;
  }
  const std::string stem = obj.stem().string();
  const fs::path dir = obj.parent_path();
  const std::string mtl_name = stem + ".mtl";

  std::vector<BlockKey> keys;
  keys.reserve(submeshes.size());
  for (const auto& [key, mesh] : submeshes) keys.push_back(key);
  std::sort(keys.begin(), keys.end());

  // A patch is used only if it matches its submesh (one UV per vertex).
  std::vector<BlockKey> textured;
  std::vector<cv::Size> sizes;
  std::vector<cv::Mat> images;
  for (const BlockKey& key : keys) {
    const auto it = patches.find(key);
    if (it == patches.end() || it->second.uvs.size() != submeshes.at(key).positions.size() ||
        it->second.image_rgb.empty())
      continue;
    textured.push_back(key);
    sizes.push_back(it->second.image_rgb.size());
    images.push_back(it->second.image_rgb);
  }
  const AtlasLayout layout = packAtlas(sizes, options.atlas_edge_px, options.gutter_px);
  const std::vector<cv::Mat> atlases = renderAtlases(layout, images, options.gutter_px);
  for (size_t i = 0; i < textured.size(); ++i) info->placements[textured[i]] = layout.placements[i];

  std::vector<std::string> atlas_names;
  for (size_t k = 0; k < atlases.size(); ++k) {
    atlas_names.push_back(stem + "_atlas_" + std::to_string(k) + ".png");
    const std::string path = (dir / atlas_names.back()).string();
    cv::Mat bgr;
    cv::cvtColor(atlases[k], bgr, cv::COLOR_RGB2BGR);
    bool ok = false;
    try {
      ok = cv::imwrite(path, bgr);
    } catch (const cv::Exception&) {
    }
    if (!ok) {
      *error = path + ": cannot write the atlas image";
      return false;
    }
    info->files.push_back(path);
  }

  const std::string mtl_path = (dir / mtl_name).string();
  {
    File mtl(std::fopen(mtl_path.c_str(), "w"));
    if (!mtl) {
      *error = mtl_path + ": cannot open for writing";
      return false;
    }
    std::fprintf(mtl.get(), "# stereo_fusion texture atlases\n");
    for (size_t k = 0; k < atlases.size(); ++k)
      std::fprintf(mtl.get(), "newmtl atlas_%zu\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nillum 1\nmap_Kd %s\n\n", k,
                   atlas_names[k].c_str());
    std::fprintf(mtl.get(), "newmtl vertex_colour\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nillum 1\n");
    if (std::ferror(mtl.get())) {
      *error = mtl_path + ": write failed";
      return false;
    }
  }
  info->files.insert(info->files.begin(), mtl_path);

  File out(std::fopen(obj_path.c_str(), "w"));
  if (!out) {
    *error = obj_path + ": cannot open for writing";
    return false;
  }
  std::FILE* f = out.get();
  std::fprintf(f, "# stereo_fusion textured mesh: %zu blocks, %zu with a texture patch\nmtllib %s\n", keys.size(),
               textured.size(), mtl_name.c_str());
  size_t v_base = 1, vt_base = 1;  // OBJ indices are 1-based and global
  for (const BlockKey& key : keys) {
    const SubMesh& m = submeshes.at(key);
    const auto placement = info->placements.find(key);
    const bool has_texture = placement != info->placements.end();
    std::fprintf(f, "o block_%d_%d_%d\n", key.x, key.y, key.z);
    for (size_t v = 0; v < m.positions.size(); ++v)
      std::fprintf(f, "v %.6f %.6f %.6f %.4f %.4f %.4f\n", m.positions[v].x(), m.positions[v].y(),
                   m.positions[v].z(), m.colors[v][0] / 255.0, m.colors[v][1] / 255.0, m.colors[v][2] / 255.0);
    for (size_t v = 0; v < m.normals.size(); ++v)
      std::fprintf(f, "vn %.5f %.5f %.5f\n", m.normals[v].x(), m.normals[v].y(), m.normals[v].z());
    if (has_texture) {
      const AtlasPlacement& p = placement->second;
      const cv::Size atlas = layout.atlas_sizes[p.atlas];
      for (const Eigen::Vector2f& uv : patches.at(key).uvs) {
        // Patch UV (texel-edge convention, v down) → atlas texel coordinates → OBJ (v up).
        const double x = p.rect.x + uv.x() * p.rect.width, y = p.rect.y + uv.y() * p.rect.height;
        std::fprintf(f, "vt %.7f %.7f\n", x / atlas.width, 1.0 - y / atlas.height);
      }
      std::fprintf(f, "usemtl atlas_%d\n", p.atlas);
      for (const auto& t : m.triangles) {
        const size_t a = t[0], b = t[1], c = t[2];
        std::fprintf(f, "f %zu/%zu/%zu %zu/%zu/%zu %zu/%zu/%zu\n", v_base + a, vt_base + a, v_base + a, v_base + b,
                     vt_base + b, v_base + b, v_base + c, vt_base + c, v_base + c);
      }
      vt_base += m.positions.size();
      ++info->textured_blocks;
    } else {
      std::fprintf(f, "usemtl vertex_colour\n");
      for (const auto& t : m.triangles)
        std::fprintf(f, "f %zu//%zu %zu//%zu %zu//%zu\n", v_base + t[0], v_base + t[0], v_base + t[1], v_base + t[1],
                     v_base + t[2], v_base + t[2]);
      ++info->vertex_colour_blocks;
    }
    v_base += m.positions.size();
  }
  if (std::ferror(f)) {
    *error = obj_path + ": write failed";
    return false;
  }
  info->files.insert(info->files.begin(), obj_path);
  return true;
}

}  // namespace stereo_fusion
