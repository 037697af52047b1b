#include "stereo_fusion/paging/BlockPage.h"

#include <array>

namespace stereo_fusion {

namespace {
// No array in a page is larger than a submesh of one block can be (a block holds 8³ cells of
// at most 5 triangles and 12 edges each, plus its seams): a count beyond it is corruption.
constexpr size_t kMaxElements = 1 << 20;
}  // namespace

void writePageHead(const VoxelBlock& block, uint64_t last_update_frame, ByteWriter* out) {
  out->put(kBlockPageMagic);
  out->put(kBlockPageVersion);
  out->put(block.key.x);
  out->put(block.key.y);
  out->put(block.key.z);
  out->put(last_update_frame);
  uint8_t mask = 0;
  for (int l = 0; l < kNumLevels; ++l) mask |= static_cast<uint8_t>(block.hasLevel(l) << l);
  out->put(mask);
  for (int l = 0; l < kNumLevels; ++l)
    if (block.hasLevel(l)) out->putBytes(block.level(l), levelVoxelCount(l) * sizeof(Voxel));
}

std::unique_ptr<VoxelBlock> readPageHead(ByteReader* in, const BlockKey& expected,
                                         uint64_t* last_update_frame, std::string* error) {
  const uint32_t magic = in->get<uint32_t>();
  const uint32_t version = in->get<uint32_t>();
  if (!in->ok() || magic != kBlockPageMagic || version != kBlockPageVersion) {
    *error = "not a block page of this version";
    return nullptr;
  }
  BlockKey key;
  key.x = in->get<int32_t>();
  key.y = in->get<int32_t>();
  key.z = in->get<int32_t>();
  *last_update_frame = in->get<uint64_t>();
  const uint8_t mask = in->get<uint8_t>();
  if (!in->ok() || key != expected || mask > 0b111) {
    *error = "the page does not hold the block it is filed under";
    return nullptr;
  }
  auto block = std::make_unique<VoxelBlock>();
  block->key = key;
  std::array<Voxel, 512> voxels;
  for (int l = 0; l < kNumLevels; ++l) {
    if (!(mask & (1u << l))) continue;
    in->getBytes(voxels.data(), levelVoxelCount(l) * sizeof(Voxel));
    if (!in->ok()) {
      *error = "the page is cut short";
      return nullptr;
    }
    block->adoptLevel(l, voxels.data());
  }
  return block;
}

bool skipPageHead(ByteReader* in) {
  in->skip(2 * sizeof(uint32_t) + 3 * sizeof(int32_t) + sizeof(uint64_t));
  const uint8_t mask = in->get<uint8_t>();
  for (int l = 0; l < kNumLevels; ++l)
    if (mask & (1u << l)) in->skip(levelVoxelCount(l) * sizeof(Voxel));
  return in->ok() && mask <= 0b111;
}

void writeSubMesh(const SubMesh& mesh, ByteWriter* out) {
  out->put(mesh.key.x);
  out->put(mesh.key.y);
  out->put(mesh.key.z);
  out->put<int32_t>(mesh.level);
  out->putArray(mesh.positions);
  out->putArray(mesh.normals);
  out->putArray(mesh.colors);
  out->putArray(mesh.triangles);
}

bool readSubMesh(ByteReader* in, SubMesh* mesh) {
  mesh->key.x = in->get<int32_t>();
  mesh->key.y = in->get<int32_t>();
  mesh->key.z = in->get<int32_t>();
  mesh->level = in->get<int32_t>();
  return in->getArray(&mesh->positions, kMaxElements) &&
         in->getArray(&mesh->normals, kMaxElements) && in->getArray(&mesh->colors, kMaxElements) &&
         in->getArray(&mesh->triangles, kMaxElements) && mesh->level >= 0 &&
         mesh->level < kNumLevels;
}

void writeTexturePatch(const TexturePatch& patch, ByteWriter* out) {
  const cv::Mat image = patch.image_rgb.isContinuous() ? patch.image_rgb : patch.image_rgb.clone();
  out->put<int32_t>(image.rows);
  out->put<int32_t>(image.cols);
  out->put<int32_t>(image.type());
  out->putBytes(image.data, image.total() * image.elemSize());
  out->putArray(patch.uvs);
  const Eigen::Matrix4d T = patch.T_camera_world.matrix();
  out->putBytes(T.data(), sizeof(double) * 16);
  for (double v : {patch.fx_px, patch.fy_px, patch.cx_px, patch.cy_px, patch.crop_origin_px.x(),
                   patch.crop_origin_px.y(), patch.crop_size_px.x(), patch.crop_size_px.y(),
                   patch.score_px2_per_m2})
    out->put(v);
  out->put(patch.frame_index);
}

bool readTexturePatch(ByteReader* in, TexturePatch* patch) {
  const int32_t rows = in->get<int32_t>(), cols = in->get<int32_t>(), type = in->get<int32_t>();
  if (!in->ok() || rows < 0 || cols < 0 || rows > 4096 || cols > 4096 || type != CV_8UC3)
    return in->fail();
  patch->image_rgb.create(rows, cols, type);
  in->getBytes(patch->image_rgb.data, patch->image_rgb.total() * patch->image_rgb.elemSize());
  if (!in->getArray(&patch->uvs, kMaxElements)) return false;
  Eigen::Matrix4d T;
  in->getBytes(T.data(), sizeof(double) * 16);
  patch->T_camera_world.matrix() = T;
  patch->fx_px = in->get<double>();
  patch->fy_px = in->get<double>();
  patch->cx_px = in->get<double>();
  patch->cy_px = in->get<double>();
  patch->crop_origin_px.x() = in->get<double>();
  patch->crop_origin_px.y() = in->get<double>();
  patch->crop_size_px.x() = in->get<double>();
  patch->crop_size_px.y() = in->get<double>();
  patch->score_px2_per_m2 = in->get<double>();
  patch->frame_index = in->get<uint64_t>();
  return in->ok();
}

}  // namespace stereo_fusion
