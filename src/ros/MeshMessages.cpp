#include "stereo_fusion/ros/MeshMessages.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace stereo_fusion {

bool parseMeshEncoding(const std::string& text, MeshEncoding* encoding) {
  if (text == "float32")
    *encoding = MeshEncoding::kFloat32;
  else if (text == "compact")
    *encoding = MeshEncoding::kCompact;
  else
    return false;
  return true;
}

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

/// Largest texture patch edge a subscriber accepts: the maximum of texture_max_patch_px.
constexpr uint32_t kMaxPatchEdgePx = 1024;

/// Decodes a block's PNG patch to RGB; false for anything that is not a PNG of at most
/// kMaxPatchEdgePx per edge. The size is read from the IHDR chunk before decoding because a
/// decoder sizes its image from the header: a 64-byte message can claim 100000² px (30 GB).
/// OpenCV's own limit (2^30 px by default, 3 GB of RGB) is far above any patch, and what it
/// does near it differs between versions; a patch above the cap is a corrupt message anyway.
bool decodeTexture(const std::vector<uint8_t>& png, cv::Mat* rgb) {
  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  // Signature (8), then the first chunk must be IHDR: length (4), "IHDR" (4), width, height (4 +
  // 4).
  if (png.size() < 24 || !std::equal(kSignature, kSignature + 8, png.begin()) ||
      !std::equal(png.begin() + 12, png.begin() + 16, "IHDR"))
    return false;
  auto bigEndian = [&](size_t at) {
    return uint32_t{png[at]} << 24 | uint32_t{png[at + 1]} << 16 | uint32_t{png[at + 2]} << 8 |
           uint32_t{png[at + 3]};
  };
  const uint32_t width = bigEndian(16), height = bigEndian(20);
  if (width == 0 || height == 0 || width > kMaxPatchEdgePx || height > kMaxPatchEdgePx)
    return false;
  cv::Mat bgr;
  try {
    bgr = cv::imdecode(png, cv::IMREAD_COLOR);
  } catch (const cv::Exception&) {
    return false;  // corrupt data OpenCV refuses by throwing rather than returning an empty image
  }
  if (bgr.empty() || bgr.type() != CV_8UC3 || bgr.cols != static_cast<int>(width) ||
      bgr.rows != static_cast<int>(height))
    return false;
  cv::cvtColor(bgr, *rgb, cv::COLOR_BGR2RGB);
  return true;
}

/// `from`'s elements (each three `T`s, packed) as one flat array: one copy, not a push per value
/// (at 1 cm a 10 Hz update took 2.8 ms to build element by element).
template <typename T, typename Triple>
void assignFlat(const std::vector<Triple>& from, std::vector<T>* to) {
  static_assert(sizeof(Triple) == 3 * sizeof(T), "a triple of T, without padding");
  const T* first = from.empty() ? nullptr : &from.front()[0];
  to->assign(first, first + 3 * from.size());
}

/// The reverse of assignFlat(): `from` (a multiple of three values) as packed triples.
template <typename Triple, typename T>
void assignTriples(const std::vector<T>& from, std::vector<Triple>* to) {
  static_assert(sizeof(Triple) == 3 * sizeof(T), "a triple of T, without padding");
  to->resize(from.size() / 3);
  if (!to->empty()) std::memcpy(&to->front()[0], from.data(), to->size() * sizeof(Triple));
}

/// Fills the compact fields of `b` from `s`; false (b's compact fields then unspecified) when a
/// vertex is outside the quantised range or there are too many vertices for uint16 indices.
bool encodeCompact(const SubMesh& s, double block_size_m, MeshBlock* b) {
  if (!(block_size_m > 0) || s.positions.size() > std::numeric_limits<uint16_t>::max() + size_t{1})
    return false;
  const double step = compactPositionStep(block_size_m);
  const Eigen::Vector3d origin(s.key.x * block_size_m, s.key.y * block_size_m,
                               s.key.z * block_size_m);
  b->position_step_m = static_cast<float>(step);
  b->vertices_q.reserve(3 * s.positions.size());
  b->normals_q.reserve(3 * s.normals.size());
  for (size_t v = 0; v < s.positions.size(); ++v) {
    for (int k = 0; k < 3; ++k) {
      const double q = std::round((s.positions[v][k] - origin[k]) / step);
      if (!(q >= 0.0 && q <= 65535.0)) return false;
      b->vertices_q.push_back(static_cast<uint16_t>(q));
      const float n = std::max(-1.0f, std::min(1.0f, s.normals[v][k]));
      b->normals_q.push_back(static_cast<int8_t>(std::lround(n * 127.0f)));
    }
  }
  b->triangles_q.reserve(3 * s.triangles.size());
  for (const auto& t : s.triangles) b->triangles_q.insert(b->triangles_q.end(), t.begin(), t.end());
  return true;
}

}  // namespace

MeshBlock toMeshBlock(const SubMesh& s, MeshEncoding encoding, double block_size_m,
                      const TexturePatch* patch) {
  MeshBlock b;
  b.key = {s.key.x, s.key.y, s.key.z};
  b.level = static_cast<uint8_t>(s.level);
  b.position_step_m = 0.0f;
  // The texture is independent of how the geometry is encoded: attached on every path.
  if (patch && patch->uvs.size() == s.positions.size() && !patch->image_rgb.empty())
    encodeTexture(*patch, &b);
  if (encoding == MeshEncoding::kCompact) {
    if (encodeCompact(s, block_size_m, &b)) {
      assignFlat(s.colors, &b.colors);
      return b;
    }
    b.position_step_m = 0.0f;  // does not fit: this block goes as float32
    b.vertices_q.clear();
    b.normals_q.clear();
    b.triangles_q.clear();
  }
  assignFlat(s.positions, &b.vertices);
  assignFlat(s.normals, &b.normals);
  assignFlat(s.colors, &b.colors);
  assignFlat(s.triangles, &b.triangles);
  return b;
}

MeshUpdate toMeshUpdate(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                        const std::vector<BlockKey>& changed, const std::vector<BlockKey>& removed,
                        const std_msgs::Header& header, double voxel_size_m, uint64_t sequence,
                        bool full, MeshEncoding encoding, const TextureStore* textures) {
  return toMeshUpdate(submeshes, changed, removed, header, voxel_size_m, sequence, full, encoding,
                      textures ? &textures->patches() : nullptr);
}

MeshUpdate toMeshUpdate(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                        const std::vector<BlockKey>& changed, const std::vector<BlockKey>& removed,
                        const std_msgs::Header& header, double voxel_size_m, uint64_t sequence,
                        bool full, MeshEncoding encoding,
                        const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* patches) {
  MeshUpdate u;
  u.header = header;
  u.sequence = sequence;
  u.full = full;
  u.voxel_size = static_cast<float>(voxel_size_m);
  u.block_size = static_cast<float>(8.0 * voxel_size_m);
  for (const BlockKey& key : changed) {
    auto it = submeshes.find(key);
    if (it == submeshes.end()) continue;
    const TexturePatch* patch = nullptr;
    if (patches) {
      auto p = patches->find(key);
      if (p != patches->end()) patch = &p->second;
    }
    u.blocks.push_back(toMeshBlock(it->second, encoding, u.block_size, patch));
  }
  for (const BlockKey& key : removed)
    u.removed_keys.insert(u.removed_keys.end(), {key.x, key.y, key.z});
  return u;
}

bool applyMeshUpdate(const MeshUpdate& update,
                     std::unordered_map<BlockKey, SubMesh, BlockKeyHash>* mesh,
                     std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* textures) {
  // Validate everything first: a malformed message leaves the mesh untouched.
  // block_size places compact vertices; a float32 update does not use it, but a non-finite
  // one is corrupt either way.
  if (update.removed_keys.size() % 3 != 0 || !std::isfinite(update.block_size)) return false;
  for (const MeshBlock& b : update.blocks) {
    if (b.level > 2) return false;  // 8³, 4³, 2³: nothing else is sampled
    size_t n = 0;
    if (b.position_step_m > 0) {
      n = b.vertices_q.size() / 3;
      if (!(update.block_size > 0) || !std::isfinite(b.position_step_m) ||
          b.vertices_q.size() % 3 || b.normals_q.size() != 3 * n || b.colors.size() != 3 * n ||
          b.triangles_q.size() % 3)
        return false;
      for (uint16_t index : b.triangles_q)
        if (index >= n) return false;
    } else {
      n = b.vertices.size() / 3;
      if (b.vertices.size() % 3 || b.normals.size() != 3 * n || b.colors.size() != 3 * n ||
          b.triangles.size() % 3)
        return false;
      for (uint32_t index : b.triangles)
        if (index >= n) return false;
    }
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
      if (!decodeTexture(b.texture.data, &decoded[i])) return false;
    }
  }
  if (update.full) {
    mesh->clear();
    if (textures) textures->clear();
  }
  for (size_t i = 0; i < update.removed_keys.size(); i += 3) {
    const BlockKey key{update.removed_keys[i], update.removed_keys[i + 1],
                       update.removed_keys[i + 2]};
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
    SubMesh s;
    s.key = {b.key[0], b.key[1], b.key[2]};
    s.level = b.level;
    if (b.position_step_m > 0) {
      const double block = update.block_size;
      const Eigen::Vector3d origin(s.key.x * block, s.key.y * block, s.key.z * block);
      const size_t n = b.vertices_q.size() / 3;
      for (size_t v = 0; v < n; ++v) {
        Eigen::Vector3d p, normal;
        for (int k = 0; k < 3; ++k) {
          p[k] = origin[k] + b.vertices_q[3 * v + k] * static_cast<double>(b.position_step_m);
          normal[k] = b.normals_q[3 * v + k] / 127.0;
        }
        if (normal.norm() > 0) normal.normalize();
        s.positions.push_back(p.cast<float>());
        s.normals.push_back(normal.cast<float>());
      }
      assignTriples(b.colors, &s.colors);
      for (size_t t = 0; t < b.triangles_q.size(); t += 3)
        s.triangles.push_back({b.triangles_q[t], b.triangles_q[t + 1], b.triangles_q[t + 2]});
      (*mesh)[s.key] = std::move(s);
      continue;
    }
    // Sizes checked above: three values per vertex in each field, three indices per triangle.
    assignTriples(b.vertices, &s.positions);
    assignTriples(b.normals, &s.normals);
    assignTriples(b.colors, &s.colors);
    assignTriples(b.triangles, &s.triangles);
    (*mesh)[s.key] = std::move(s);
  }
  return true;
}

int MeshMarkers::idOf(const BlockKey& key) {
  auto [it, inserted] = ids_.try_emplace(key, next_id_);
  if (inserted) ++next_id_;
  return it->second;
}

visualization_msgs::MarkerArray MeshMarkers::build(
    const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
    const std::vector<BlockKey>& changed, const std::vector<BlockKey>& removed,
    const std_msgs::Header& header) {
  visualization_msgs::MarkerArray array;
  for (const BlockKey& key : changed) {
    auto it = submeshes.find(key);
    if (it == submeshes.end()) continue;
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
    // Forgotten, or every block ever drawn would keep an entry (eviction runs for hours). Ids
    // are not reused (next_id_ only grows), so a DELETE still in flight cannot hit a newer block.
    ids_.erase(it);
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
