// Fuzz target: applyMeshUpdate (what the base station's MeshAssembler and any subscriber run on
// every ~mesh_update) on messages built from arbitrary bytes: float32 and compact blocks with
// any counts, indices, levels, floats (NaN, infinities), UVs, texture bytes (a real PNG header
// half the time), removed keys and block sizes. An update it accepts leaves a mesh whose every
// triangle indexes its block's vertices and whose every patch has a UV per vertex; one it
// refuses leaves the mesh and the textures exactly as they were.
#include <opencv2/imgcodecs.hpp>

#include "FuzzSupport.h"
#include "stereo_fusion/ros/MeshMessages.h"

using namespace stereo_fusion;

namespace {

/// A small valid PNG (2×2), so that half the texture bytes reach the decoder's pixel path.
const std::vector<uint8_t>& smallPng() {
  static const std::vector<uint8_t> png = [] {
    std::vector<uint8_t> bytes;
    cv::imencode(".png", cv::Mat(2, 2, CV_8UC3, cv::Scalar(10, 20, 30)), bytes);
    return bytes;
  }();
  return png;
}

MeshBlock readBlock(fuzz::ByteReader* in) {
  MeshBlock b;
  for (int k = 0; k < 3; ++k) b.key[k] = static_cast<int8_t>(in->u8());
  b.level = in->u8() % 5;  // 3 and 4 are invalid
  const size_t vertices = in->u8() % 24, triangles = in->u8() % 24;
  const uint8_t shape =
      in->u8();  // bit 0: compact; bits 1-3: break one array's size; bit 4: uvs; bit 5: png
  const bool compact = shape & 1;
  const int broken = (shape >> 1) & 7;  // 0-4: sizes as required, 5-7: one array off by one
  const size_t n = vertices;
  if (compact) {
    b.position_step_m = in->u8() % 4 == 0 ? in->f32() : static_cast<float>(in->scaled(1e-4, 1e-2));
    for (size_t i = 0; i < 3 * n + (broken == 5); ++i)
      b.vertices_q.push_back(static_cast<uint16_t>(in->u8() << 4));
    for (size_t i = 0; i < 3 * n + (broken == 6); ++i)
      b.normals_q.push_back(static_cast<int8_t>(in->u8()));
    for (size_t i = 0; i < 3 * triangles; ++i)
      b.triangles_q.push_back(in->u8() % (n + 2));  // some out of range
  } else {
    for (size_t i = 0; i < 3 * n + (broken == 5); ++i)
      b.vertices.push_back(in->u8() % 8 == 0 ? in->f32() : in->u8() * 0.01f);
    for (size_t i = 0; i < 3 * n + (broken == 6); ++i)
      b.normals.push_back(in->u8() % 8 == 0 ? in->f32() : 0.5f);
    for (size_t i = 0; i < 3 * triangles; ++i) b.triangles.push_back(in->u8() % (n + 2));
  }
  for (size_t i = 0; i < 3 * n + (broken == 7); ++i) b.colors.push_back(in->u8());
  if (shape & 16) {
    for (size_t i = 0; i < 2 * n; ++i)
      b.uvs.push_back(in->u8() % 16 == 0 ? in->f32() : in->u8() / 255.0f);
    if (shape & 32) {
      b.texture.data = smallPng();
      for (int k = in->u8() % 4; k > 0; --k)
        b.texture.data[in->u8() % b.texture.data.size()] = in->u8();
    } else {
      for (int k = in->u8() % 32; k > 0; --k) b.texture.data.push_back(in->u8());
    }
  }
  return b;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::ByteReader in(data, size);
  // What a subscriber already holds: a first, well-formed update of one triangle.
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> mesh;
  std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> textures;
  {
    MeshUpdate first;
    first.block_size = 0.16f;
    MeshBlock b;
    b.key = {{1, 2, 3}};
    b.vertices = {0, 0, 0, 0.1f, 0, 0, 0, 0.1f, 0};
    b.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    b.colors = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    b.triangles = {0, 1, 2};
    first.blocks.push_back(b);
    fuzz::require(applyMeshUpdate(first, &mesh, &textures));
  }
  const auto mesh_before = mesh;
  const size_t textures_before = textures.size();

  MeshUpdate update;
  update.full = in.u8() % 4 == 0;
  update.block_size = in.u8() % 8 == 0 ? in.f32() : static_cast<float>(in.scaled(0.01, 1.0));
  for (int k = in.u8() % 4; k > 0; --k) update.blocks.push_back(readBlock(&in));
  for (int k = in.u8() % 8; k > 0; --k) update.removed_keys.push_back(static_cast<int8_t>(in.u8()));

  if (!applyMeshUpdate(update, &mesh, &textures)) {
    fuzz::require(mesh.size() == mesh_before.size() && textures.size() == textures_before);
    for (const auto& [key, sub] : mesh_before) {
      const auto it = mesh.find(key);
      fuzz::require(it != mesh.end() && it->second.positions.size() == sub.positions.size() &&
                    it->second.triangles.size() == sub.triangles.size());
    }
    return 0;
  }
  for (const auto& [key, sub] : mesh) {
    for (const auto& t : sub.triangles)
      for (int k = 0; k < 3; ++k) fuzz::require(static_cast<size_t>(t[k]) < sub.positions.size());
    fuzz::require(sub.level <= 2);
  }
  for (const auto& [key, patch] : textures) {
    const auto it = mesh.find(key);
    fuzz::require(it != mesh.end() && patch.uvs.size() == it->second.positions.size() &&
                  !patch.image_rgb.empty());
    for (const auto& uv : patch.uvs)
      fuzz::require(uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1);
  }
  return 0;
}
