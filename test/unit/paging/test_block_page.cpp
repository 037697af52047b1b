// A block's page: its voxels and last update frame, a submesh and a texture patch come back
// bit for bit; a page of another key, or cut short, is refused with a sentence.
#include <gtest/gtest.h>

#include <cstring>

#include "stereo_fusion/paging/BlockPage.h"

using namespace stereo_fusion;

namespace {
VoxelBlock sampleBlock() {
  VoxelBlock block;
  block.key = {-3, 4, 1000};
  // Only the two coarse levels, as a far block holds them.
  for (int l = 1; l < kNumLevels; ++l) {
    Voxel* voxels = block.writableLevel(l);
    for (int n = 0; n < levelVoxelCount(l); ++n) {
      voxels[n].sdf_m = 0.001f * n - 0.01f;
      voxels[n].weight = static_cast<float>(n % 5);
      voxels[n].r = static_cast<uint8_t>(n);
      voxels[n].g = static_cast<uint8_t>(2 * n);
      voxels[n].b = static_cast<uint8_t>(3 * n);
    }
  }
  return block;
}
}  // namespace

TEST(BlockPage, VoxelsAndLastUpdateFrameRoundTripExactly) {
  const VoxelBlock block = sampleBlock();
  std::vector<uint8_t> bytes;
  ByteWriter writer(&bytes);
  writePageHead(block, 77, &writer);
  // 4 + 4 magic and version, 12 key, 8 frame, 1 levels, (64 + 8) voxels of 12 B.
  EXPECT_EQ(bytes.size(), 29u + 72u * 12u);
  ByteReader reader(bytes.data(), bytes.size());
  uint64_t frame = 0;
  std::string error;
  const std::unique_ptr<VoxelBlock> back = readPageHead(&reader, block.key, &frame, &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(frame, 77u);
  EXPECT_EQ(back->key, block.key);
  EXPECT_FALSE(back->hasLevel(0)) << "a level the block did not hold stays unallocated";
  for (int l = 1; l < kNumLevels; ++l)
    EXPECT_EQ(std::memcmp(back->level(l), block.level(l), levelVoxelCount(l) * sizeof(Voxel)), 0);
  EXPECT_EQ(reader.remaining(), 0u);
  ByteReader skipping(bytes.data(), bytes.size());
  EXPECT_TRUE(skipPageHead(&skipping));
  EXPECT_EQ(skipping.remaining(), 0u);
}

TEST(BlockPage, AnotherKeyOrAShortPageIsRefused) {
  const VoxelBlock block = sampleBlock();
  std::vector<uint8_t> bytes;
  ByteWriter writer(&bytes);
  writePageHead(block, 1, &writer);
  uint64_t frame = 0;
  std::string error;
  ByteReader other(bytes.data(), bytes.size());
  EXPECT_FALSE(readPageHead(&other, {0, 0, 0}, &frame, &error));
  EXPECT_NE(error.find("does not hold the block"), std::string::npos) << error;
  for (size_t cut : {size_t{0}, size_t{6}, size_t{30}, bytes.size() - 1}) {
    error.clear();
    ByteReader shorter(bytes.data(), cut);
    EXPECT_FALSE(readPageHead(&shorter, block.key, &frame, &error)) << cut;
    EXPECT_FALSE(error.empty()) << cut;
  }
}

TEST(BlockPage, SubmeshAndTexturePatchRoundTripExactly) {
  SubMesh mesh;
  mesh.key = {1, -2, 3};
  mesh.level = 1;
  mesh.positions = {{0.1f, 0.2f, 0.3f}, {1, 2, 3}, {-1, 0.5f, 7}};
  mesh.normals = {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}};
  mesh.colors = {{{1, 2, 3}}, {{4, 5, 6}}, {{7, 8, 9}}};
  mesh.triangles = {{{0, 1, 2}}};
  TexturePatch patch;
  patch.image_rgb = cv::Mat(5, 7, CV_8UC3);
  for (size_t n = 0; n < patch.image_rgb.total() * 3; ++n)
    patch.image_rgb.data[n] = static_cast<uint8_t>(37 * n + 11);
  patch.uvs = {{0.1f, 0.2f}, {0.3f, 0.4f}, {0.5f, 0.6f}};
  patch.T_camera_world.translation() = Eigen::Vector3d(1, 2, 3);
  patch.fx_px = 500.5;
  patch.cy_px = 120.25;
  patch.crop_origin_px = {10, 20};
  patch.crop_size_px = {70, 50};
  patch.score_px2_per_m2 = 1234.5;
  patch.frame_index = 42;
  std::vector<uint8_t> bytes;
  ByteWriter writer(&bytes);
  writeSubMesh(mesh, &writer);
  writeTexturePatch(patch, &writer);
  ByteReader reader(bytes.data(), bytes.size());
  SubMesh mesh_back;
  TexturePatch patch_back;
  ASSERT_TRUE(readSubMesh(&reader, &mesh_back));
  ASSERT_TRUE(readTexturePatch(&reader, &patch_back));
  EXPECT_EQ(reader.remaining(), 0u);
  EXPECT_EQ(mesh_back.key, mesh.key);
  EXPECT_EQ(mesh_back.level, 1);
  EXPECT_EQ(mesh_back.positions, mesh.positions);
  EXPECT_EQ(mesh_back.normals, mesh.normals);
  EXPECT_EQ(mesh_back.colors, mesh.colors);
  EXPECT_EQ(mesh_back.triangles, mesh.triangles);
  ASSERT_EQ(patch_back.image_rgb.size(), patch.image_rgb.size());
  EXPECT_EQ(std::memcmp(patch_back.image_rgb.data, patch.image_rgb.data, 5 * 7 * 3), 0);
  EXPECT_EQ(patch_back.uvs, patch.uvs);
  EXPECT_TRUE(patch_back.T_camera_world.isApprox(patch.T_camera_world, 0.0));
  EXPECT_EQ(patch_back.fx_px, 500.5);
  EXPECT_EQ(patch_back.cy_px, 120.25);
  EXPECT_EQ(patch_back.crop_origin_px, patch.crop_origin_px);
  EXPECT_EQ(patch_back.crop_size_px, patch.crop_size_px);
  EXPECT_EQ(patch_back.score_px2_per_m2, 1234.5);
  EXPECT_EQ(patch_back.frame_index, 42u);
  // A count that claims more than the page holds is refused, not read past the end.
  bytes.resize(30);
  ByteReader cut(bytes.data(), bytes.size());
  EXPECT_FALSE(readSubMesh(&cut, &mesh_back));
}
