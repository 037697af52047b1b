#include "stereo_fusion/ros/MeshMessages.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace stereo_fusion {

namespace {

/// compressed_image_transport's format string: original encoding; codec and stored encoding.
constexpr const char* kTextureFormat = "rgb8; png compressed bgr8";

void encodeTexture(const TexturePatch& patch, MeshBlock* b) {
  cv::Mat bgr;
  cv::cvtColor(patch.image_rgb, bgr, cv::COLOR_RGB2BGR);
  // Level 1: patches are small and published often; speed matters more than the last bytes.
  cv::imencode(".png", bgr, b->texture.data, {cv::IMWRITE_PNG_COMPRESSION, 1});
  b->texture.format = kTextureFormat;
  b->uvs.reserve(2 * patch.uvs.size());
  for (const Eigen::Vector2f& uv : patch.uvs) b->uvs.insert(b->uvs.end(), {uv.x(), uv.y()});
}

}  // namespace

MeshBlock toMeshBlock(const SubMesh& s, const TexturePatch* patch) {
  MeshBlock b;
  b.key = {s.key.x, s.key.y, s.key.z};
  b.level = static_cast<uint8_t>(s.level);
  b.vertices.reserve(3 * s.positions.size());
  b.normals.reserve(3 * s.normals.size());
  b.colors.reserve(3 * s.colors.size());
  for (size_t v = 0; v < s.positions.size(); ++v) {
    for (int k = 0; k < 3; ++k) {
      b.vertices.push_back(s.positions[v][k]);
      b.normals.push_back(s.normals[v][k]);
      b.colors.push_back(s.colors[v][k]);
    }
  }
  b.triangles.reserve(3 * s.triangles.size());
  for (const auto& t : s.triangles) b.triangles.insert(b.triangles.end(), t.begin(), t.end());
  if (patch && patch->uvs.size() == s.positions.size() && !patch->image_rgb.empty()) encodeTexture(*patch, &b);
  return b;
}

MeshUpdate toMeshUpdate(const MeshStore& store, const std::vector<BlockKey>& changed,
                        const std::vector<BlockKey>& removed, const std_msgs::Header& header,
                        double voxel_size_m, uint64_t sequence, bool full, const TextureStore* textures) {
  MeshUpdate u;
  u.header = header;
  u.sequence = sequence;
  u.full = full;
  u.voxel_size = static_cast<float>(voxel_size_m);
  u.block_size = static_cast<float>(8.0 * voxel_size_m);
  for (const BlockKey& key : changed) {
    auto it = store.submeshes().find(key);
    if (it != store.submeshes().end())
      u.blocks.push_back(toMeshBlock(it->second, textures ? textures->find(key) : nullptr));
  }
  for (const BlockKey& key : removed) u.removed_keys.insert(u.removed_keys.end(), {key.x, key.y, key.z});
  return u;
}

bool applyMeshUpdate(const MeshUpdate& update, std::unordered_map<BlockKey, SubMesh, BlockKeyHash>* mesh,
                     std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* textures) {
  // Validate everything first: a malformed message leaves the mesh untouched.
  if (update.removed_keys.size() % 3 != 0) return false;
  for (const MeshBlock& b : update.blocks) {
    const size_t n = b.vertices.size() / 3;
    if (b.vertices.size() % 3 || b.normals.size() != 3 * n || b.colors.size() != 3 * n || b.triangles.size() % 3)
      return false;
    for (uint32_t index : b.triangles)
      if (index >= n) return false;
    if (!b.uvs.empty() && (b.uvs.size() != 2 * n || b.texture.data.empty())) return false;
    for (float c : b.uvs)
      if (!(c >= 0.0f && c <= 1.0f)) return false;
  }
  // Decode the textures before touching anything, so a corrupt PNG also changes nothing.
  std::vector<cv::Mat> decoded(update.blocks.size());
  if (textures) {
    for (size_t i = 0; i < update.blocks.size(); ++i) {
      const MeshBlock& b = update.blocks[i];
      if (b.uvs.empty()) continue;
      const cv::Mat bgr = cv::imdecode(b.texture.data, cv::IMREAD_COLOR);
      if (bgr.empty()) return false;
      cv::cvtColor(bgr, decoded[i], cv::COLOR_BGR2RGB);
    }
  }
  if (update.full) {
    mesh->clear();
    if (textures) textures->clear();
  }
  for (size_t i = 0; i < update.removed_keys.size(); i += 3) {
    const BlockKey key{update.removed_keys[i], update.removed_keys[i + 1], update.removed_keys[i + 2]};
    mesh->erase(key);
    if (textures) textures->erase(key);
  }
  if (textures) {
    for (size_t i = 0; i < update.blocks.size(); ++i) {
      const MeshBlock& b = update.blocks[i];
      const BlockKey key{b.key[0], b.key[1], b.key[2]};
      if (b.uvs.empty()) {
        textures->erase(key);
        continue;
      }
      TexturePatch& patch = (*textures)[key];
      patch = TexturePatch{};
      patch.image_rgb = decoded[i];
      for (size_t v = 0; v < b.uvs.size(); v += 2) patch.uvs.emplace_back(b.uvs[v], b.uvs[v + 1]);
    }
  }
  for (const MeshBlock& b : update.blocks) {
    const size_t n = b.vertices.size() / 3;
    SubMesh s;
    s.key = {b.key[0], b.key[1], b.key[2]};
    s.level = b.level;
    for (size_t v = 0; v < n; ++v) {
      s.positions.emplace_back(b.vertices[3 * v], b.vertices[3 * v + 1], b.vertices[3 * v + 2]);
      s.normals.emplace_back(b.normals[3 * v], b.normals[3 * v + 1], b.normals[3 * v + 2]);
      s.colors.push_back({b.colors[3 * v], b.colors[3 * v + 1], b.colors[3 * v + 2]});
    }
    for (size_t t = 0; t < b.triangles.size(); t += 3)
      s.triangles.push_back({b.triangles[t], b.triangles[t + 1], b.triangles[t + 2]});
    (*mesh)[s.key] = std::move(s);
  }
  return true;
}

int MeshMarkers::idOf(const BlockKey& key) {
  auto [it, inserted] = ids_.try_emplace(key, next_id_);
  if (inserted) ++next_id_;
  return it->second;
}

visualization_msgs::MarkerArray MeshMarkers::build(const MeshStore& store, const std::vector<BlockKey>& changed,
                                                   const std::vector<BlockKey>& removed,
                                                   const std_msgs::Header& header) {
  visualization_msgs::MarkerArray array;
  for (const BlockKey& key : changed) {
    auto it = store.submeshes().find(key);
    if (it == store.submeshes().end()) continue;
    const SubMesh& s = it->second;
    visualization_msgs::Marker m;
    m.header = header;
    m.ns = "mesh";
    m.id = idOf(key);
    m.type = visualization_msgs::Marker::TRIANGLE_LIST;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = m.scale.z = 1.0;
    m.color.a = 1.0f;
    m.points.reserve(3 * s.triangles.size());
    m.colors.reserve(3 * s.triangles.size());
    for (const auto& t : s.triangles)
      for (uint32_t v : t) {
        geometry_msgs::Point p;
        p.x = s.positions[v].x();
        p.y = s.positions[v].y();
        p.z = s.positions[v].z();
        m.points.push_back(p);
        std_msgs::ColorRGBA c;
        c.r = s.colors[v][0] / 255.0f;
        c.g = s.colors[v][1] / 255.0f;
        c.b = s.colors[v][2] / 255.0f;
        c.a = 1.0f;
        m.colors.push_back(c);
      }
    array.markers.push_back(std::move(m));
  }
  for (const BlockKey& key : removed) {
    auto it = ids_.find(key);
    if (it == ids_.end()) continue;
    visualization_msgs::Marker m;
    m.header = header;
    m.ns = "mesh";
    m.id = it->second;
    m.action = visualization_msgs::Marker::DELETE;
    array.markers.push_back(m);
  }
  return array;
}

visualization_msgs::MarkerArray MeshMarkers::clear(const std_msgs::Header& header) {
  visualization_msgs::MarkerArray array;
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = "mesh";
  m.action = visualization_msgs::Marker::DELETEALL;
  array.markers.push_back(m);
  ids_.clear();
  next_id_ = 0;
  return array;
}

}  // namespace stereo_fusion
