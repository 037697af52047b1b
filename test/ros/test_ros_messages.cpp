// Message builders of the ROS layer, checked with numbers (linked into the fusion_nodelet rostest
// binary; these cases need no master): the compact MeshBlock encoding, textures on both
// encodings, the decoder's input checks and the markers.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>

#include "stereo_fusion/ros/DebugMarkers.h"
#include "stereo_fusion/ros/MarkerSender.h"
#include "stereo_fusion/ros/SendThread.h"
#include "stereo_fusion/ros/MeshMessages.h"

using namespace stereo_fusion;

namespace {

constexpr double kBlockM = 0.16;  // 2 cm voxels

/// A submesh of block `key` with `n` vertices spread over [origin, origin + 1.5 blocks) per
/// axis (a level-2 block's seam reaches half a block into its neighbours), random unit normals.
SubMesh randomSubmesh(const BlockKey& key, size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> offset(0.0, 1.5 * kBlockM), unit(-1.0, 1.0);
  SubMesh s;
  s.key = key;
  s.level = 2;
  for (size_t v = 0; v < n; ++v) {
    s.positions.emplace_back(Eigen::Vector3d(key.x * kBlockM + offset(rng),
                                             key.y * kBlockM + offset(rng),
                                             key.z * kBlockM + offset(rng))
                                 .cast<float>());
    s.normals.push_back(
        Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized().cast<float>());
    s.colors.push_back(
        {static_cast<uint8_t>(v), static_cast<uint8_t>(2 * v), static_cast<uint8_t>(3 * v)});
  }
  for (size_t v = 0; v + 2 < n; v += 3)
    s.triangles.push_back({uint32_t(v), uint32_t(v + 1), uint32_t(v + 2)});
  return s;
}

MeshUpdate updateOf(const SubMesh& s, MeshEncoding encoding) {
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> store{{s.key, s}};
  return toMeshUpdate(store, {s.key}, {}, std_msgs::Header(), kBlockM / 8.0, 1, false, encoding);
}

}  // namespace

// float32: each vertex's x y z, normal and colour in vertex order, the triangles' indices in
// triangle order — hand-set values; applyMeshUpdate() reads them back exactly.
TEST(Float32Encoding, FieldsAreTheSubmeshFlattenedInOrder) {
  SubMesh s;
  s.key = {2, -1, 5};
  s.level = 1;
  s.positions = {{0.5f, -1.25f, 3.0f}, {0.75f, -1.0f, 3.125f}, {1.0f, -1.5f, 2.875f}};
  s.normals = {{0.0f, 0.0f, -1.0f}, {0.6f, 0.0f, -0.8f}, {0.0f, 1.0f, 0.0f}};
  s.colors = {{{1, 2, 3}}, {{40, 50, 60}}, {{255, 0, 128}}};
  s.triangles = {{{0, 1, 2}}, {{2, 1, 0}}};
  const MeshBlock b = toMeshBlock(s, MeshEncoding::kFloat32, kBlockM, nullptr);
  EXPECT_EQ(b.vertices,
            (std::vector<float>{0.5f, -1.25f, 3.0f, 0.75f, -1.0f, 3.125f, 1.0f, -1.5f, 2.875f}));
  EXPECT_EQ(b.normals,
            (std::vector<float>{0.0f, 0.0f, -1.0f, 0.6f, 0.0f, -0.8f, 0.0f, 1.0f, 0.0f}));
  EXPECT_EQ(b.colors, (std::vector<uint8_t>{1, 2, 3, 40, 50, 60, 255, 0, 128}));
  EXPECT_EQ(b.triangles, (std::vector<uint32_t>{0, 1, 2, 2, 1, 0}));
  EXPECT_EQ(b.level, 1);
  // And read back by a subscriber, field for field.
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> mesh;
  ASSERT_TRUE(applyMeshUpdate(updateOf(s, MeshEncoding::kFloat32), &mesh));
  const SubMesh& d = mesh.at(s.key);
  EXPECT_EQ(d.positions, s.positions);
  EXPECT_EQ(d.normals, s.normals);
  EXPECT_EQ(d.colors, s.colors);
  EXPECT_EQ(d.triangles, s.triangles);
  EXPECT_EQ(d.level, 1);
  const SubMesh empty_mesh;
  const MeshBlock e = toMeshBlock(empty_mesh, MeshEncoding::kFloat32, kBlockM, nullptr);
  EXPECT_TRUE(e.vertices.empty() && e.normals.empty() && e.colors.empty() && e.triangles.empty());
}

TEST(CompactEncoding, RoundTripWithinHalfAStep) {
  const SubMesh s = randomSubmesh({-3, 7, 120}, 3000, 1);
  const MeshUpdate u = updateOf(s, MeshEncoding::kCompact);
  ASSERT_EQ(u.blocks.size(), 1u);
  const MeshBlock& b = u.blocks[0];
  EXPECT_FLOAT_EQ(b.position_step_m, static_cast<float>(kBlockM / 32768.0));
  EXPECT_TRUE(b.vertices.empty() && b.normals.empty() && b.triangles.empty());
  EXPECT_EQ(b.vertices_q.size(), 9000u);
  EXPECT_EQ(b.triangles_q.size(), 3000u);
  // 6 + 3 + 3 bytes per vertex and 6 per triangle instead of 12 + 12 + 3 and 12.
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> mesh;
  ASSERT_TRUE(applyMeshUpdate(u, &mesh));
  const SubMesh& d = mesh.at(s.key);
  ASSERT_EQ(d.positions.size(), s.positions.size());
  EXPECT_EQ(d.triangles, s.triangles);
  EXPECT_EQ(d.colors, s.colors);
  EXPECT_EQ(d.level, 2);
  double worst_m = 0, worst_normal_rad = 0;
  for (size_t v = 0; v < s.positions.size(); ++v) {
    worst_m = std::max(
        worst_m, static_cast<double>((d.positions[v] - s.positions[v]).cwiseAbs().maxCoeff()));
    worst_normal_rad =
        std::max(worst_normal_rad, std::acos(std::min(1.0f, d.normals[v].dot(s.normals[v]))) + 0.0);
    EXPECT_NEAR(d.normals[v].norm(), 1.0f, 1e-5f);
  }
  // Half a step (2.44 µm) plus float32 rounding of coordinates near 19 m (key z = 120).
  EXPECT_LE(worst_m, kBlockM / 32768.0 / 2.0 + 2e-6);
  EXPECT_GT(worst_m, 1e-7);            // really quantised
  EXPECT_LT(worst_normal_rad, 0.012);  // int8: ≤ 0.5/127 per component
}

TEST(CompactEncoding, BlocksThatDoNotFitGoAsFloat32) {
  SubMesh below = randomSubmesh({0, 0, 0}, 30, 2);
  below.positions[5].x() = -0.001f;  // 1 mm before the block origin: not representable
  SubMesh huge = randomSubmesh({1, 0, 0}, 65537, 3);  // too many vertices for uint16 indices
  for (const SubMesh* s : {&below, &huge}) {
    const MeshUpdate u = updateOf(*s, MeshEncoding::kCompact);
    const MeshBlock& b = u.blocks.at(0);
    EXPECT_EQ(b.position_step_m, 0.0f);
    EXPECT_TRUE(b.vertices_q.empty() && b.normals_q.empty() && b.triangles_q.empty());
    std::unordered_map<BlockKey, SubMesh, BlockKeyHash> mesh;
    ASSERT_TRUE(applyMeshUpdate(u, &mesh));
    EXPECT_EQ(mesh.at(s->key).positions, s->positions);  // float32: exact
    EXPECT_EQ(mesh.at(s->key).triangles, s->triangles);
  }
}

TEST(CompactEncoding, MalformedMessagesLeaveTheMeshUntouched) {
  const SubMesh s = randomSubmesh({0, 0, 0}, 30, 4);
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> mesh{{{9, 9, 9}, s}};
  MeshUpdate bad_index = updateOf(s, MeshEncoding::kCompact);
  bad_index.blocks[0].triangles_q[4] = 30;  // one past the last vertex
  EXPECT_FALSE(applyMeshUpdate(bad_index, &mesh));
  MeshUpdate short_normals = updateOf(s, MeshEncoding::kCompact);
  short_normals.blocks[0].normals_q.pop_back();
  EXPECT_FALSE(applyMeshUpdate(short_normals, &mesh));
  MeshUpdate no_block_size = updateOf(s, MeshEncoding::kCompact);
  no_block_size.block_size = 0.0f;
  EXPECT_FALSE(applyMeshUpdate(no_block_size, &mesh));
  ASSERT_EQ(mesh.size(), 1u);
  EXPECT_EQ(mesh.count({9, 9, 9}), 1u);
}

namespace {

/// A patch for `s`: a w×h gradient and one UV per vertex spread over [0, 1]².
TexturePatch patchFor(const SubMesh& s, int w = 12, int h = 9) {
  TexturePatch patch;
  patch.image_rgb.create(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      patch.image_rgb.at<cv::Vec3b>(y, x) = cv::Vec3b(20 * x, 25 * y, 7 * (x + y));
  for (size_t v = 0; v < s.positions.size(); ++v)
    patch.uvs.emplace_back(static_cast<float>(v % 7) / 6.0f, static_cast<float>(v % 5) / 4.0f);
  return patch;
}

using SubmeshMap = std::unordered_map<BlockKey, SubMesh, BlockKeyHash>;
using PatchMap = std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>;

}  // namespace

// texture: patches with mesh_encoding: compact used to publish no patch at all (the compact
// branch returned before the texture was attached).
TEST(Textures, CompactBlocksCarryTheirPatch) {
  const SubMesh s = randomSubmesh({2, -1, 5}, 30, 5);
  const TexturePatch patch = patchFor(s);
  const MeshBlock b = toMeshBlock(s, MeshEncoding::kCompact, kBlockM, &patch);
  EXPECT_GT(b.position_step_m, 0.0f);  // really the compact path
  EXPECT_EQ(b.uvs.size(), 2 * s.positions.size());
  EXPECT_FALSE(b.texture.data.empty());
  EXPECT_EQ(b.texture.format, "rgb8; png compressed bgr8");

  // Round trip through an update: the same texels and UVs come back.
  MeshUpdate u;
  u.voxel_size = static_cast<float>(kBlockM / 8.0);
  u.block_size = static_cast<float>(kBlockM);
  u.blocks.push_back(b);
  SubmeshMap mesh;
  PatchMap textures;
  ASSERT_TRUE(applyMeshUpdate(u, &mesh, &textures));
  ASSERT_EQ(textures.count(s.key), 1u);
  const TexturePatch& got = textures.at(s.key);
  ASSERT_EQ(got.image_rgb.size(), patch.image_rgb.size());
  EXPECT_EQ(cv::norm(got.image_rgb, patch.image_rgb, cv::NORM_INF), 0.0);
  EXPECT_EQ(got.uvs, patch.uvs);
  EXPECT_EQ(mesh.at(s.key).triangles, s.triangles);
}

// toMeshUpdate with a plain key → patch map (what the assembler holds, it has no TextureStore)
// attaches each block's patch exactly as toMeshBlock does, in both encodings.
TEST(Textures, UpdateFromAPatchMapCarriesThePatches) {
  const SubMesh s = randomSubmesh({0, 1, 2}, 24, 6);
  const SubmeshMap store{{s.key, s}};
  const PatchMap patches{{s.key, patchFor(s)}};
  for (MeshEncoding encoding : {MeshEncoding::kFloat32, MeshEncoding::kCompact}) {
    const MeshUpdate u = toMeshUpdate(store, {s.key}, {}, std_msgs::Header(), kBlockM / 8.0, 3,
                                      true, encoding, &patches);
    ASSERT_EQ(u.blocks.size(), 1u);
    const MeshBlock expected = toMeshBlock(s, encoding, kBlockM, &patches.at(s.key));
    EXPECT_EQ(u.blocks[0].uvs, expected.uvs);
    EXPECT_EQ(u.blocks[0].texture.data, expected.texture.data);
    EXPECT_FALSE(u.blocks[0].texture.data.empty());
  }
}

namespace {

/// A PNG signature and IHDR chunk declaring `width`×`height` 8-bit RGB, zero-padded to 64 bytes
/// (no image data: a decoder that trusts the header allocates width·height·3 bytes first).
std::vector<uint8_t> pngHeader(uint32_t width, uint32_t height) {
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n',
                              0,    0,   0,   13,  'I',  'H',  'D',  'R'};
  for (uint32_t value : {width, height})
    for (int shift = 24; shift >= 0; shift -= 8)
      png.push_back(static_cast<uint8_t>(value >> shift));
  png.insert(png.end(), {8, 2, 0, 0,
                         0});  // bit depth 8, colour type 2 (RGB), deflate, no filter, no interlace
  png.resize(64, 0);
  return png;
}

/// An update holding `s` whose texture is `png`, with valid UVs.
MeshUpdate texturedUpdate(const SubMesh& s, const std::vector<uint8_t>& png) {
  const TexturePatch patch = patchFor(s);
  MeshUpdate u;
  u.voxel_size = static_cast<float>(kBlockM / 8.0);
  u.block_size = static_cast<float>(kBlockM);
  u.blocks.push_back(toMeshBlock(s, MeshEncoding::kFloat32, kBlockM, &patch));
  u.blocks[0].texture.data = png;
  return u;
}

}  // namespace

// A tiny PNG whose header declares a huge image must be refused before decoding (a decoder that
// trusts it allocates 30 GB), as must a valid PNG larger than texture_max_patch_px allows and
// data that is no PNG; the mesh and the patches stay untouched.
TEST(Textures, OversizedOrForeignImagesAreRefused) {
  const SubMesh s = randomSubmesh({1, 1, 1}, 30, 7);
  const SubMesh held = randomSubmesh({4, 4, 4}, 30, 8);
  SubmeshMap mesh{{held.key, held}};
  PatchMap textures{{held.key, patchFor(held)}};

  EXPECT_FALSE(applyMeshUpdate(texturedUpdate(s, pngHeader(100000, 100000)), &mesh, &textures));
  // 30000² px = 2.7 GB: below OpenCV's own limit of 2^30 px, which refuses only the case above.
  EXPECT_FALSE(applyMeshUpdate(texturedUpdate(s, pngHeader(30000, 30000)), &mesh, &textures));
  // Valid and small on the wire (a flat image compresses to a few kB), but 1025 px wide.
  std::vector<uint8_t> wide;
  ASSERT_TRUE(cv::imencode(".png", cv::Mat(8, 1025, CV_8UC3, cv::Scalar(1, 2, 3)), wide));
  EXPECT_LT(wide.size(), 1000u);
  EXPECT_FALSE(applyMeshUpdate(texturedUpdate(s, wide), &mesh, &textures));
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", cv::Mat(8, 8, CV_8UC3, cv::Scalar(1, 2, 3)), jpeg));
  EXPECT_FALSE(applyMeshUpdate(texturedUpdate(s, jpeg), &mesh, &textures));
  ASSERT_EQ(mesh.size(), 1u);
  EXPECT_EQ(mesh.at(held.key).positions, held.positions);
  ASSERT_EQ(textures.size(), 1u);
  EXPECT_EQ(textures.at(held.key).image_rgb.cols, 12);

  // The guard lets through what the robot sends: 1024 px per edge at most.
  std::vector<uint8_t> largest;
  ASSERT_TRUE(cv::imencode(".png", cv::Mat(1024, 4, CV_8UC3, cv::Scalar(1, 2, 3)), largest));
  ASSERT_TRUE(applyMeshUpdate(texturedUpdate(s, largest), &mesh, &textures));
  EXPECT_EQ(textures.at(s.key).image_rgb.rows, 1024);
}

// A compact block with block_size = inf decodes to infinite positions, NaN to NaN, and a level
// above 2 does not exist: all refused, in both encodings, without touching the mesh.
TEST(Validation, NonFiniteBlockSizeAndUnknownLevelsAreRefused) {
  const SubMesh s = randomSubmesh({0, 0, 0}, 30, 9);
  const SubMesh held = randomSubmesh({9, 9, 9}, 30, 10);
  SubmeshMap mesh{{held.key, held}};
  for (MeshEncoding encoding : {MeshEncoding::kCompact, MeshEncoding::kFloat32}) {
    for (float block_size :
         {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()}) {
      MeshUpdate u = updateOf(s, encoding);
      u.block_size = block_size;
      EXPECT_FALSE(applyMeshUpdate(u, &mesh)) << static_cast<int>(encoding) << " " << block_size;
    }
    MeshUpdate level3 = updateOf(s, encoding);
    level3.blocks[0].level = 3;
    EXPECT_FALSE(applyMeshUpdate(level3, &mesh)) << static_cast<int>(encoding);
    MeshUpdate level2 = updateOf(s, encoding);  // the largest valid level still goes through
    SubmeshMap other;
    EXPECT_TRUE(applyMeshUpdate(level2, &other));
  }
  ASSERT_EQ(mesh.size(), 1u);
  EXPECT_EQ(mesh.at(held.key).positions, held.positions);
}

// Every block ever drawn used to keep its id forever: with eviction over hours the map grew
// without bound. A DELETE forgets the id.
TEST(MeshMarkers, IdsOfRemovedBlocksAreForgotten) {
  SubmeshMap store;
  MeshMarkers markers;
  std::set<int> ids;
  for (int i = 0; i < 5000; ++i) {
    const BlockKey key{i, -i, 3};
    store[key] = randomSubmesh(key, 3, i);
    const auto added = markers.build(store, {key}, {}, std_msgs::Header());
    ASSERT_EQ(added.markers.size(), 1u);
    EXPECT_EQ(added.markers[0].action, visualization_msgs::Marker::ADD);
    ids.insert(added.markers[0].id);
    ASSERT_EQ(markers.size(), 1u) << i;
    store.erase(key);
    const auto removed = markers.build(store, {}, {key}, std_msgs::Header());
    ASSERT_EQ(removed.markers.size(), 1u);
    EXPECT_EQ(removed.markers[0].action, visualization_msgs::Marker::DELETE);
    EXPECT_EQ(removed.markers[0].id, added.markers[0].id);  // deletes what was drawn
  }
  EXPECT_EQ(markers.size(), 0u);
  EXPECT_EQ(ids.size(), 5000u);  // ids are not reused: a late DELETE cannot hit a newer block
}

// Jobs run one at a time in the order posted, off the poster's thread; one that throws is
// logged and the next still runs; flush() returns once all have run.
TEST(SendThread, RunsJobsInOrderAndGoesOnAfterAFailure) {
  std::vector<int> ran;  // written by the send thread only, read after flush()
  std::atomic<int> running{0}, most_at_once{0};
  const std::thread::id poster = std::this_thread::get_id();
  std::atomic<bool> on_poster{false};
  SendThread thread("test jobs");
  for (int i = 0; i < 200; ++i)
    thread.post([&, i] {
      most_at_once = std::max(most_at_once.load(), ++running);
      if (std::this_thread::get_id() == poster) on_poster = true;
      if (i == 50) {
        --running;
        throw std::runtime_error("job 50 fails");
      }
      ran.push_back(i);
      --running;
    });
  thread.flush();
  EXPECT_TRUE(thread.idle());
  ASSERT_EQ(ran.size(), 199u);
  for (size_t k = 0; k < ran.size(); ++k) EXPECT_EQ(ran[k], static_cast<int>(k < 50 ? k : k + 1));
  EXPECT_EQ(most_at_once.load(), 1);
  EXPECT_FALSE(on_poster.load());
}

// The sender builds on its own thread what was handed over, from copies taken at hand-over,
// in the order handed over: a reset's DELETEALL after the markers before it, before those after.
TEST(MarkerSender, SendsCopiesInTheOrderHandedOver) {
  const BlockKey a{1, 2, 3}, b{-4, 0, 7};
  SubmeshMap store;
  store[a] = randomSubmesh(a, 30, 11);
  store[b] = randomSubmesh(b, 30, 12);
  std::mutex mutex;
  std::vector<visualization_msgs::MarkerArray> sent;
  MarkerSender sender([&](const visualization_msgs::MarkerArray& markers) {
    std::lock_guard<std::mutex> lock(mutex);
    sent.push_back(markers);
  });
  std_msgs::Header header;
  header.seq = 1;
  sender.send(store, {a, b}, {}, header);
  const size_t a_corners = 3 * store[a].triangles.size();
  store[a] = randomSubmesh(a, 60, 13);  // changed after the hand-over
  store.erase(b);
  header.seq = 2;
  sender.sendClear(header);
  header.seq = 3;
  sender.send(store, {a, b}, {}, header);  // b has no submesh now: skipped
  sender.flush();
  EXPECT_TRUE(sender.idle());
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_EQ(sent.size(), 3u);
  ASSERT_EQ(sent[0].markers.size(), 2u);
  EXPECT_EQ(sent[0].markers[0].header.seq, 1u);
  EXPECT_EQ(sent[0].markers[0].action, visualization_msgs::Marker::ADD);
  EXPECT_EQ(sent[0].markers[0].points.size(), a_corners);  // the copy, not the later submesh
  ASSERT_EQ(sent[1].markers.size(), 1u);
  EXPECT_EQ(sent[1].markers[0].action, visualization_msgs::Marker::DELETEALL);
  ASSERT_EQ(sent[2].markers.size(), 1u);
  EXPECT_EQ(sent[2].markers[0].header.seq, 3u);
  EXPECT_EQ(sent[2].markers[0].points.size(), 3 * store[a].triangles.size());
}

TEST(DebugMarkers, FrustumCornersAtTheGivenDepth) {
  const StereoCamera camera = *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1);
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  T_world_camera.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  const visualization_msgs::Marker m =
      frustumMarker(camera, T_world_camera, 2.0, std_msgs::Header());
  EXPECT_EQ(m.type, visualization_msgs::Marker::LINE_LIST);
  ASSERT_EQ(m.points.size(), 16u);  // 4 rays + 4 far edges
  // Ray 0: optical centre → top-left image corner (pixel edge u = v = -0.5) at z = 2 m:
  // x = (-0.5 - 159.5) / 262.5 * 2 = -1.21905, y = (-0.5 - 119.5) / 262.5 * 2 = -0.91429.
  EXPECT_DOUBLE_EQ(m.points[0].x, 1.0);
  EXPECT_DOUBLE_EQ(m.points[0].z, 3.0);
  EXPECT_NEAR(m.points[1].x, 1.0 - 1.2190476, 1e-6);
  EXPECT_NEAR(m.points[1].y, 2.0 - 0.9142857, 1e-6);
  EXPECT_NEAR(m.points[1].z, 5.0, 1e-12);
  // Ray 2 ends at the bottom-right corner (u = 319.5, v = 239.5): symmetric.
  EXPECT_NEAR(m.points[9].x, 1.0 + 1.2190476, 1e-6);
  EXPECT_NEAR(m.points[9].y, 2.0 + 0.9142857, 1e-6);
}

TEST(DebugMarkers, BlockBoundsAreTheTwelveEdgesOfEachBlock) {
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> meshes;
  meshes[{1, 2, -3}].level = 1;
  const visualization_msgs::Marker m = blockBoundsMarker(meshes, kBlockM, std_msgs::Header());
  ASSERT_EQ(m.points.size(), 24u);
  ASSERT_EQ(m.colors.size(), 24u);
  EXPECT_FLOAT_EQ(m.colors[0].r, 0.9f);  // level 1: yellow
  for (size_t i = 0; i < 24; i += 2) {
    const Eigen::Vector3d a(m.points[i].x, m.points[i].y, m.points[i].z),
        b(m.points[i + 1].x, m.points[i + 1].y, m.points[i + 1].z);
    EXPECT_NEAR((b - a).norm(), kBlockM, 1e-12);  // one edge of the block, axis-aligned
    for (const Eigen::Vector3d& p : {a, b}) {
      EXPECT_TRUE(std::abs(p.x() - 0.16) < 1e-12 || std::abs(p.x() - 0.32) < 1e-12) << p.x();
      EXPECT_TRUE(std::abs(p.y() - 0.32) < 1e-12 || std::abs(p.y() - 0.48) < 1e-12) << p.y();
      EXPECT_TRUE(std::abs(p.z() + 0.48) < 1e-12 || std::abs(p.z() + 0.32) < 1e-12) << p.z();
    }
  }
  EXPECT_EQ(blockBoundsMarker({}, kBlockM, std_msgs::Header()).action,
            visualization_msgs::Marker::DELETE);
}
