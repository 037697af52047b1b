// Message builders of the ROS layer, checked with numbers (linked into the fusion_nodelet rostest
// binary; these cases need no master): the compact MeshBlock encoding and the debug markers.
#include <gtest/gtest.h>

#include <random>

#include "stereo_fusion/ros/DebugMarkers.h"
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
    s.positions.emplace_back(Eigen::Vector3d(key.x * kBlockM + offset(rng), key.y * kBlockM + offset(rng),
                                             key.z * kBlockM + offset(rng)).cast<float>());
    s.normals.push_back(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized().cast<float>());
    s.colors.push_back({static_cast<uint8_t>(v), static_cast<uint8_t>(2 * v), static_cast<uint8_t>(3 * v)});
  }
  for (size_t v = 0; v + 2 < n; v += 3) s.triangles.push_back({uint32_t(v), uint32_t(v + 1), uint32_t(v + 2)});
  return s;
}

MeshUpdate updateOf(const SubMesh& s, MeshEncoding encoding) {
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> store{{s.key, s}};
  return toMeshUpdate(store, {s.key}, {}, std_msgs::Header(), kBlockM / 8.0, 1, false, encoding);
}

}  // namespace

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
    worst_m = std::max(worst_m, static_cast<double>((d.positions[v] - s.positions[v]).cwiseAbs().maxCoeff()));
    worst_normal_rad = std::max(worst_normal_rad, std::acos(std::min(1.0f, d.normals[v].dot(s.normals[v]))) + 0.0);
    EXPECT_NEAR(d.normals[v].norm(), 1.0f, 1e-5f);
  }
  // Half a step (2.44 µm) plus float32 rounding of coordinates near 19 m (key z = 120).
  EXPECT_LE(worst_m, kBlockM / 32768.0 / 2.0 + 2e-6);
  EXPECT_GT(worst_m, 1e-7);  // really quantised
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

TEST(DebugMarkers, FrustumCornersAtTheGivenDepth) {
  const StereoCamera camera = *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1);
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  T_world_camera.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  const visualization_msgs::Marker m = frustumMarker(camera, T_world_camera, 2.0, std_msgs::Header());
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
    const Eigen::Vector3d a(m.points[i].x, m.points[i].y, m.points[i].z), b(m.points[i + 1].x, m.points[i + 1].y, m.points[i + 1].z);
    EXPECT_NEAR((b - a).norm(), kBlockM, 1e-12);  // one edge of the block, axis-aligned
    for (const Eigen::Vector3d& p : {a, b}) {
      EXPECT_TRUE(std::abs(p.x() - 0.16) < 1e-12 || std::abs(p.x() - 0.32) < 1e-12) << p.x();
      EXPECT_TRUE(std::abs(p.y() - 0.32) < 1e-12 || std::abs(p.y() - 0.48) < 1e-12) << p.y();
      EXPECT_TRUE(std::abs(p.z() + 0.48) < 1e-12 || std::abs(p.z() + 0.32) < 1e-12) << p.z();
    }
  }
  EXPECT_EQ(blockBoundsMarker({}, kBlockM, std_msgs::Header()).action, visualization_msgs::Marker::DELETE);
}
