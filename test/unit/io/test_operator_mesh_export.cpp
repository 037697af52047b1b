// The fleet's operator mesh: robots' welded meshes carried into the operator frame by their
// alignments and concatenated, nothing welded or dropped across robots.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "stereo_fusion/io/OperatorMeshExport.h"

namespace stereo_fusion {
namespace {

/// One triangle at `offset` with a colour of its own.
TriangleMesh triangle(const Eigen::Vector3f& offset, uint8_t red) {
  TriangleMesh m;
  m.positions = {offset, offset + Eigen::Vector3f(1, 0, 0), offset + Eigen::Vector3f(0, 1, 0)};
  m.normals.assign(3, Eigen::Vector3f(0, 0, 1));
  m.colors.assign(3, {red, 20, 30});
  m.triangles = {{0, 1, 2}};
  return m;
}

/// A quarter turn about z and a translation: every product in it is exact in float and double.
Eigen::Isometry3d quarterTurnAndShift(const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  T.translation() = t;
  return T;
}

TEST(OperatorMesh, PlacesEachRobotByItsOwnAlignmentAndReindexesTriangles) {
  const TriangleMesh a = triangle({0, 0, 0}, 200), b = triangle({2, 0, 0}, 100);
  const TriangleMesh placed = placeMeshes({{&a, Eigen::Isometry3d(Eigen::Translation3d(10, 0, 0))},
                                           {&b, quarterTurnAndShift({0, 5, 1})}});
  ASSERT_EQ(placed.positions.size(), 6u);
  ASSERT_EQ(placed.triangles.size(), 2u);
  // Robot a: shifted by +10 x.
  EXPECT_EQ(placed.positions[0], Eigen::Vector3f(10, 0, 0));
  EXPECT_EQ(placed.positions[1], Eigen::Vector3f(11, 0, 0));
  EXPECT_EQ(placed.positions[2], Eigen::Vector3f(10, 1, 0));
  // Robot b: (x, y, z) → (−y, x, z) + (0, 5, 1): (2,0,0) → (0,7,1), (3,0,0) → (0,8,1), (2,1,0) →
  // (−1,7,1).
  EXPECT_EQ(placed.positions[3], Eigen::Vector3f(0, 7, 1));
  EXPECT_EQ(placed.positions[4], Eigen::Vector3f(0, 8, 1));
  EXPECT_EQ(placed.positions[5], Eigen::Vector3f(-1, 7, 1));
  // Normals turn with the rotation only (a z normal stays z under a yaw).
  for (const Eigen::Vector3f& n : placed.normals) EXPECT_EQ(n, Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(placed.colors[0][0], 200);
  EXPECT_EQ(placed.colors[3][0], 100);
  EXPECT_EQ(placed.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(placed.triangles[1], (std::array<uint32_t, 3>{3, 4, 5}));
}

TEST(OperatorMesh, NormalsRotateAndOverlappingRobotsKeepBothSurfaces) {
  TriangleMesh a = triangle({0, 0, 0}, 1);
  a.normals.assign(3, Eigen::Vector3f(1, 0, 0));
  // Both robots saw the same triangle at the same operator place: both stay (no merge rule
  // that could double or drop walls).
  const TriangleMesh placed =
      placeMeshes({{&a, quarterTurnAndShift({0, 0, 0})}, {&a, quarterTurnAndShift({0, 0, 0})}});
  ASSERT_EQ(placed.triangles.size(), 2u);
  for (const Eigen::Vector3f& n : placed.normals) EXPECT_EQ(n, Eigen::Vector3f(0, 1, 0));
  for (int i = 0; i < 3; ++i) EXPECT_EQ(placed.positions[i], placed.positions[i + 3]);
}

TEST(OperatorMesh, VerticesAreTheExactTransformRoundedOnce) {
  // A rotation with inexact entries: each vertex is the double transform of the float vertex,
  // rounded once to float (what the fleet rostest's tolerance rests on).
  TriangleMesh a = triangle({0.123456f, -3.5f, 1.25f}, 7);
  const Eigen::Isometry3d T = Eigen::Translation3d(0.5, -0.25, 0.0) *
                              Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ());
  const TriangleMesh placed = placeMeshes({{&a, T}});
  for (size_t i = 0; i < a.positions.size(); ++i) {
    const Eigen::Vector3d exact = T * a.positions[i].cast<double>();
    for (int c = 0; c < 3; ++c) EXPECT_EQ(placed.positions[i][c], static_cast<float>(exact[c]));
  }
}

TEST(OperatorMesh, ExportWritesOnePlyOfAllRobots) {
  const TriangleMesh a = triangle({0, 0, 0}, 1), b = triangle({1, 1, 1}, 2);
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("stereo_fusion_operator_" + std::to_string(::getpid()) + ".ply"))
                               .string();
  std::string message;
  ASSERT_TRUE(exportOperatorMesh(
      path, {{&a, Eigen::Isometry3d::Identity()}, {&b, Eigen::Isometry3d::Identity()}}, &message))
      << message;
  EXPECT_NE(message.find("2 triangles of 2 robots"), std::string::npos) << message;
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  EXPECT_NE(bytes.str().find("element vertex 6\n"), std::string::npos);
  EXPECT_NE(bytes.str().find("element face 2\n"), std::string::npos);
  std::filesystem::remove(path);
  // A folder that does not exist: refused with the path named, nothing written.
  EXPECT_FALSE(exportOperatorMesh("/nonexistent_dir_of_stereo_fusion/x.ply",
                                  {{&a, Eigen::Isometry3d::Identity()}}, &message));
  EXPECT_NE(message.find("/nonexistent_dir_of_stereo_fusion/x.ply"), std::string::npos) << message;
}

}  // namespace
}  // namespace stereo_fusion
