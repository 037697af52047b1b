#include "stereo_fusion/io/ObjWriter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "stereo_fusion/io/WriteTarget.h"

namespace stereo_fusion {

namespace fs = std::filesystem;

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

}  // namespace

cv::Mat bakeVertexColours(const SubMesh& mesh, std::vector<Eigen::Vector2f>* corner_uvs) {
  const size_t n = mesh.triangles.size();
  const int cols = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n)))));
  const int rows = std::max(1, static_cast<int>((n + cols - 1) / cols));
  cv::Mat rgb(2 * rows, 2 * cols, CV_8UC3, cv::Scalar(0, 0, 0));
  corner_uvs->clear();
  corner_uvs->reserve(3 * n);
  auto colour = [&](uint32_t v) {
    return Eigen::Vector3i(mesh.colors[v][0], mesh.colors[v][1], mesh.colors[v][2]);
  };
  auto put = [&](int x, int y, const Eigen::Vector3i& c) {
    const Eigen::Vector3i k = c.cwiseMax(0).cwiseMin(255);
    rgb.at<cv::Vec3b>(y, x) = cv::Vec3b(k[0], k[1], k[2]);
  };
  for (size_t t = 0; t < n; ++t) {
    const int x = 2 * static_cast<int>(t % cols), y = 2 * static_cast<int>(t / cols);
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3i c0 = colour(tri[0]), c1 = colour(tri[1]), c2 = colour(tri[2]);
    put(x, y, c0);
    put(x + 1, y, c1);
    put(x, y + 1, c2);
    put(x + 1, y + 1, c1 + c2 - c0);  // bilinear over the tile is then the plane through c0, c1, c2
    const float W = static_cast<float>(rgb.cols), H = static_cast<float>(rgb.rows);
    corner_uvs->emplace_back((x + 0.5f) / W, (y + 0.5f) / H);
    corner_uvs->emplace_back((x + 1.5f) / W, (y + 0.5f) / H);
    corner_uvs->emplace_back((x + 0.5f) / W, (y + 1.5f) / H);
  }
  return rgb;
}

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

  // A patch is used only if it matches its submesh (one UV per vertex); every other block gets
  // its vertex colours baked into a small patch, so that every face has texture coordinates
  // (Open3D drops all UVs of a file where some faces have none) and one material serves all.
  std::vector<cv::Size> sizes;
  std::vector<cv::Mat> images;
  std::vector<bool> has_patch(keys.size());
  std::vector<std::vector<Eigen::Vector2f>> baked_uvs(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    const auto it = patches.find(keys[i]);
    has_patch[i] = it != patches.end() &&
                   it->second.uvs.size() == submeshes.at(keys[i]).positions.size() &&
                   !it->second.image_rgb.empty();
    images.push_back(has_patch[i] ? it->second.image_rgb
                                  : bakeVertexColours(submeshes.at(keys[i]), &baked_uvs[i]));
    sizes.push_back(images.back().size());
  }
  const AtlasLayout layout = packAtlas(sizes, options.atlas_edge_px, options.gutter_px);
  const std::vector<cv::Mat> atlases = renderAtlases(layout, images, options.gutter_px);
  for (size_t i = 0; i < keys.size(); ++i)
    if (has_patch[i]) info->placements[keys[i]] = layout.placements[i];

  std::vector<std::string> atlas_names;
  for (size_t k = 0; k < atlases.size(); ++k)
    atlas_names.push_back(stem + "_atlas_" + std::to_string(k) + ".png");
  const std::string mtl_path = (dir / mtl_name).string();
  // Every file is checked before any is written: a FIFO or a device among them stops the export
  // with nothing written.
  std::vector<std::string> targets{obj_path, mtl_path};
  for (const std::string& name : atlas_names) targets.push_back((dir / name).string());
  for (const std::string& target : targets)
    if (!isWritableTarget(target, error)) return false;
  for (size_t k = 0; k < atlases.size(); ++k) {
    const std::string path = (dir / atlas_names[k]).string();
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

  {
    File mtl(std::fopen(mtl_path.c_str(), "w"));
    if (!mtl) {
      *error = mtl_path + ": cannot open for writing";
      return false;
    }
    std::fprintf(mtl.get(), "# stereo_fusion texture atlases\n");
    for (size_t k = 0; k < atlases.size(); ++k)
      std::fprintf(mtl.get(),
                   "newmtl atlas_%zu\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nillum 1\nmap_Kd %s\n\n", k,
                   atlas_names[k].c_str());
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
  std::fprintf(f,
               "# stereo_fusion textured mesh: %zu blocks, %zu with a texture patch\nmtllib %s\n",
               keys.size(), info->placements.size(), mtl_name.c_str());
  size_t v_base = 1, vt_base = 1;  // OBJ indices are 1-based and global
  for (size_t i = 0; i < keys.size(); ++i) {
    const BlockKey& key = keys[i];
    const SubMesh& m = submeshes.at(key);
    const AtlasPlacement& p = layout.placements[i];
    const cv::Size atlas = layout.atlas_sizes[p.atlas];
    // Patch UV (texel-edge convention, v down) → atlas texel coordinates → OBJ (v up).
    auto write_vt = [&](const Eigen::Vector2f& uv) {
      const double x = p.rect.x + uv.x() * p.rect.width, y = p.rect.y + uv.y() * p.rect.height;
      std::fprintf(f, "vt %.7f %.7f\n", x / atlas.width, 1.0 - y / atlas.height);
    };
    std::fprintf(f, "o block_%d_%d_%d\n", key.x, key.y, key.z);
    for (size_t v = 0; v < m.positions.size(); ++v)
      std::fprintf(f, "v %.6f %.6f %.6f %.4f %.4f %.4f\n", m.positions[v].x(), m.positions[v].y(),
                   m.positions[v].z(), m.colors[v][0] / 255.0, m.colors[v][1] / 255.0,
                   m.colors[v][2] / 255.0);
    for (size_t v = 0; v < m.normals.size(); ++v)
      std::fprintf(f, "vn %.5f %.5f %.5f\n", m.normals[v].x(), m.normals[v].y(), m.normals[v].z());
    std::fprintf(f, "usemtl atlas_%d\n", p.atlas);
    if (has_patch[i]) {
      for (const Eigen::Vector2f& uv : patches.at(key).uvs) write_vt(uv);
      for (const auto& t : m.triangles) {
        const size_t a = t[0], b = t[1], c = t[2];
        std::fprintf(f, "f %zu/%zu/%zu %zu/%zu/%zu %zu/%zu/%zu\n", v_base + a, vt_base + a,
                     v_base + a, v_base + b, vt_base + b, v_base + b, v_base + c, vt_base + c,
                     v_base + c);
      }
      vt_base += m.positions.size();
      ++info->textured_blocks;
    } else {
      for (const Eigen::Vector2f& uv : baked_uvs[i]) write_vt(uv);
      for (size_t t = 0; t < m.triangles.size(); ++t) {
        const auto& tri = m.triangles[t];
        const size_t c = vt_base + 3 * t;  // one vt per triangle corner
        std::fprintf(f, "f %zu/%zu/%zu %zu/%zu/%zu %zu/%zu/%zu\n", v_base + tri[0], c,
                     v_base + tri[0], v_base + tri[1], c + 1, v_base + tri[1], v_base + tri[2],
                     c + 2, v_base + tri[2]);
      }
      vt_base += 3 * m.triangles.size();
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
