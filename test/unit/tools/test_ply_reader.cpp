// PLY reading: round trips with the writer, ASCII and big-endian files written by hand, and
// clean errors (never a crash) for missing, truncated, malformed and garbage files.

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <random>
#include <string>

#include "readers/PlyReader.h"
#include "stereo_fusion/io/PlyWriter.h"

namespace stereo_fusion {
namespace {

std::string tempPath(const std::string& name) {
  return testing::TempDir() + "stereo_fusion_ply_reader_" + name;
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// A small mesh with distinct normals and colours: a square (two triangles) plus an apex.
TriangleMesh sampleMesh() {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, -1.25f}};
  mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0.6f, 0.8f}, {0, 0, 1}, {1, 0, 0}};
  mesh.colors = {{{255, 0, 0}}, {{0, 255, 0}}, {{0, 0, 255}}, {{10, 20, 30}}, {{1, 2, 3}}};
  mesh.triangles = {{{0, 1, 2}}, {{0, 2, 3}}, {{0, 1, 4}}};
  return mesh;
}

TEST(PlyReader, BinaryRoundTripWithWriter) {
  const TriangleMesh mesh = sampleMesh();
  const std::string path = tempPath("roundtrip.ply");
  std::string error;
  ASSERT_TRUE(writePly(path, mesh, &error)) << error;
  TriangleMesh read;
  ASSERT_TRUE(readPly(path, &read, &error)) << error;
  ASSERT_EQ(read.positions.size(), mesh.positions.size());
  ASSERT_EQ(read.normals.size(), mesh.normals.size());
  ASSERT_EQ(read.colors.size(), mesh.colors.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    EXPECT_EQ(read.positions[i], mesh.positions[i]);
    EXPECT_EQ(read.normals[i], mesh.normals[i]);
    EXPECT_EQ(read.colors[i], mesh.colors[i]);
  }
  EXPECT_EQ(read.triangles, mesh.triangles);
}

TEST(PlyReader, AsciiWithDoublesQuadsAndExtraElements) {
  // Double coordinates, float normals absent, uchar colours, an unknown vertex property,
  // a quad and a pentagon (fan-triangulated), an unknown element and CRLF line ends.
  const std::string path = tempPath("ascii.ply");
  writeBytes(path,
             "ply\r\nformat ascii 1.0\r\ncomment hand written\r\n"
             "element vertex 5\r\n"
             "property double x\r\nproperty double y\r\nproperty double z\r\n"
             "property float confidence\r\n"
             "property uchar red\r\nproperty uchar green\r\nproperty uchar blue\r\n"
             "element face 2\r\nproperty list uchar int vertex_indices\r\n"
             "element camera 1\r\nproperty float fov\r\n"
             "end_header\r\n"
             "0 0 0 0.5 255 0 0\r\n"
             "1 0 0 0.5 0 255 0\r\n"
             "1 1 0.125 0.5 0 0 255\r\n"
             "0 1 -2.5e-1 0.5 7 8 9\r\n"
             "0.5 1.5 0 0.5 1 1 1\r\n"
             "4 0 1 2 3\r\n"
             "5 0 1 2 4 3\r\n"
             "60.0\r\n");
  TriangleMesh mesh;
  std::string error;
  ASSERT_TRUE(readPly(path, &mesh, &error)) << error;
  ASSERT_EQ(mesh.positions.size(), 5u);
  EXPECT_EQ(mesh.positions[2], Eigen::Vector3f(1, 1, 0.125f));
  EXPECT_EQ(mesh.positions[3], Eigen::Vector3f(0, 1, -0.25f));
  EXPECT_TRUE(mesh.normals.empty());
  ASSERT_EQ(mesh.colors.size(), 5u);
  EXPECT_EQ(mesh.colors[3], (std::array<uint8_t, 3>{7, 8, 9}));
  const std::vector<std::array<uint32_t, 3>> expected = {
      {0, 1, 2}, {0, 2, 3}, {0, 1, 2}, {0, 2, 4}, {0, 4, 3}};
  EXPECT_EQ(mesh.triangles, expected);
}

TEST(PlyReader, BigEndianBinaryWithUintIndices) {
  const auto big32 = [](const void* value) {
    char bytes[4];
    std::memcpy(bytes, value, 4);
    return std::string{bytes[3], bytes[2], bytes[1], bytes[0]};
  };
  std::string body;
  const float coordinates[3][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0.5f}};
  for (const auto& vertex : coordinates) {
    for (const float c : vertex) body += big32(&c);
  }
  body += '\x03';  // uchar count
  for (const uint32_t index : {2u, 1u, 0u}) body += big32(&index);
  const std::string path = tempPath("big_endian.ply");
  writeBytes(path,
             "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\n"
             "property float y\nproperty float z\nelement face 1\n"
             "property list uchar uint vertex_indices\nend_header\n" +
                 body);
  TriangleMesh mesh;
  std::string error;
  ASSERT_TRUE(readPly(path, &mesh, &error)) << error;
  ASSERT_EQ(mesh.positions.size(), 3u);
  EXPECT_EQ(mesh.positions[2], Eigen::Vector3f(0, 3, 0.5f));
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{2, 1, 0}));
}

TEST(PlyReader, MissingFileNamesTheFile) {
  TriangleMesh mesh;
  std::string error;
  const std::string path = tempPath("does_not_exist.ply");
  EXPECT_FALSE(readPly(path, &mesh, &error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
}

TEST(PlyReader, TruncatedBinaryIsACleanError) {
  const std::string path = tempPath("truncated.ply");
  std::string error;
  ASSERT_TRUE(writePly(path, sampleMesh(), &error)) << error;
  const std::string full = readBytes(path);
  writeBytes(path, full.substr(0, full.size() - 5));
  TriangleMesh mesh;
  EXPECT_FALSE(readPly(path, &mesh, &error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  EXPECT_TRUE(mesh.positions.empty() && mesh.triangles.empty());
}

TEST(PlyReader, MalformedHeadersAndBodiesAreCleanErrors) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"empty", ""},
      {"not ply", "hello world\n"},
      {"no end_header", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"},
      {"unsupported format", "ply\nformat binary_middle_endian 1.0\nend_header\n"},
      {"unknown type", "ply\nformat ascii 1.0\nelement vertex 1\nproperty half x\nend_header\n"},
      {"no xyz", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n"},
      {"absurd count",
       "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\n"
       "property float x\nproperty float y\nproperty float z\nend_header\n0000"},
      {"negative count", "ply\nformat ascii 1.0\nelement vertex -3\nend_header\n"},
      {"index out of range", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"},
      {"negative index", header + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"},
      {"not a number", header + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n"},
      {"fractional index", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n"},
      {"short list", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n"},
      {"non-finite vertex", header + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"},
  };
  for (const auto& [name, contents] : cases) {
    const std::string path = tempPath("malformed.ply");
    writeBytes(path, contents);
    TriangleMesh mesh;
    std::string error;
    EXPECT_FALSE(readPly(path, &mesh, &error)) << name;
    EXPECT_EQ(error.rfind(path + ": ", 0), 0u) << name << ": " << error;
  }
}

TEST(PlyReader, EveryPrefixAndRandomCorruptionNeverCrashes) {
  const std::string path = tempPath("fuzz.ply");
  std::string error;
  ASSERT_TRUE(writePly(path, sampleMesh(), &error)) << error;
  const std::string full = readBytes(path);
  // Every truncation point: a clean failure, except the complete file.
  for (size_t length = 0; length < full.size(); ++length) {
    writeBytes(path, full.substr(0, length));
    TriangleMesh mesh;
    EXPECT_FALSE(readPly(path, &mesh, &error)) << "prefix of " << length << " bytes";
  }
  // Random byte flips: success or a clean failure, and any mesh read is self-consistent.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 500; ++trial) {
    std::string corrupted = full;
    for (int flips = 0; flips < 3; ++flips) {
      corrupted[rng() % corrupted.size()] = static_cast<char>(rng() & 0xFF);
    }
    writeBytes(path, corrupted);
    TriangleMesh mesh;
    if (readPly(path, &mesh, &error)) {
      for (const auto& triangle : mesh.triangles) {
        for (const uint32_t index : triangle) ASSERT_LT(index, mesh.positions.size());
      }
    } else {
      EXPECT_FALSE(error.empty());
    }
  }
}

}  // namespace
}  // namespace stereo_fusion
