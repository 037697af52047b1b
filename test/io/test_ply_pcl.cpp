// The PLY we write must load in the tools users have: PCL's reader is the one we can run here.
#include <gtest/gtest.h>
#include <pcl/PolygonMesh.h>
#include <pcl/io/ply_io.h>

#include <cstdio>
#include <fstream>
#include <set>

#include "stereo_fusion/io/PlyWriter.h"

using namespace stereo_fusion;

namespace {
TriangleMesh tetrahedron() {
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.normals = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (auto& n : m.normals) n.normalize();
  m.colors = {{{255, 0, 0}}, {{0, 255, 0}}, {{0, 0, 255}}, {{10, 20, 30}}};
  m.triangles = {{{0, 2, 1}}, {{0, 1, 3}}, {{0, 3, 2}}, {{1, 2, 3}}};
  return m;
}
}  // namespace

TEST(PlyWriter, PclLoadsVerticesFacesNormalsAndColours) {
  const std::string path = testing::TempDir() + "stereo_fusion_tetra.ply";
  std::string error;
  ASSERT_TRUE(writePly(path, tetrahedron(), &error)) << error;
  pcl::PolygonMesh mesh;
  ASSERT_EQ(pcl::io::loadPLYFile(path, mesh), 0);
  EXPECT_EQ(mesh.cloud.width * mesh.cloud.height, 4u);
  ASSERT_EQ(mesh.polygons.size(), 4u);
  ASSERT_EQ(mesh.polygons[3].vertices.size(), 3u);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(static_cast<int>(mesh.polygons[3].vertices[k]), k + 1);
  std::set<std::string> fields;
  for (const auto& f : mesh.cloud.fields) fields.insert(f.name);
  for (const char* name : {"x", "y", "z", "normal_x", "normal_y", "normal_z", "rgb"})
    EXPECT_TRUE(fields.count(name)) << "missing field " << name;
  std::remove(path.c_str());
}

TEST(PlyWriter, HeaderIsBinaryLittleEndianWithExactCounts) {
  const std::string path = testing::TempDir() + "stereo_fusion_header.ply";
  std::string error;
  ASSERT_TRUE(writePly(path, tetrahedron(), &error)) << error;
  std::ifstream in(path, std::ios::binary);
  std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t end = all.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = all.substr(0, end);
  EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(header.find("element vertex 4\n"), std::string::npos);
  EXPECT_NE(header.find("element face 4\n"), std::string::npos);
  // 4 vertices × 27 bytes + 4 faces × 13 bytes after the header.
  EXPECT_EQ(all.size() - (end + 11), 4u * 27u + 4u * 13u);
  std::remove(path.c_str());
}

TEST(PlyWriter, UnwritablePathIsAClearError) {
  std::string error;
  EXPECT_FALSE(writePly("/nonexistent-dir/mesh.ply", tetrahedron(), &error));
  EXPECT_NE(error.find("/nonexistent-dir/mesh.ply"), std::string::npos) << error;
}
