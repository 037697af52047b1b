#include "stereo_fusion/io/PlyWriter.h"

#include "stereo_fusion/io/WriteTarget.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <vector>

namespace stereo_fusion {

bool writePly(const std::string& path, const TriangleMesh& mesh, std::string* error) {
  static_assert(sizeof(float) == 4 && sizeof(int32_t) == 4);
  std::ofstream out(path, std::ios::binary);
  if (!out) {
    *error = path + ": cannot open for writing";
    return false;
  }
  out << "ply\nformat binary_little_endian 1.0\ncomment stereo_fusion mesh\n"
      << "element vertex " << mesh.positions.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "property float nx\nproperty float ny\nproperty float nz\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      << "element face " << mesh.triangles.size() << "\n"
      << "property list uchar int vertex_indices\nend_header\n";
  // Written in chunks of whole records: as fast as one buffer per element, without holding a
  // second copy of a large mesh. x86 and ARM are little-endian like the file.
  constexpr size_t kChunkRecords = 1 << 16;
  std::vector<char> buffer;
  auto writeRecords = [&](size_t count, size_t record_bytes, auto&& fill) {
    for (size_t begin = 0; begin < count; begin += kChunkRecords) {
      const size_t end = std::min(count, begin + kChunkRecords);
      buffer.resize((end - begin) * record_bytes);
      for (size_t i = begin; i < end; ++i) fill(i, buffer.data() + (i - begin) * record_bytes);
      out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    }
  };
  writeRecords(mesh.positions.size(), 6 * 4 + 3, [&](size_t v, char* p) {
    std::memcpy(p, mesh.positions[v].data(), 12);
    std::memcpy(p + 12, mesh.normals[v].data(), 12);
    std::memcpy(p + 24, mesh.colors[v].data(), 3);
  });
  writeRecords(mesh.triangles.size(), 1 + 3 * 4, [&](size_t f, char* p) {
    p[0] = 3;
    for (int k = 0; k < 3; ++k) {
      const int32_t index = static_cast<int32_t>(mesh.triangles[f][k]);
      std::memcpy(p + 1 + 4 * k, &index, 4);
    }
  });
  if (!out) {
    *error = path + ": write failed (disk full?)";
    return false;
  }
  return true;
}

bool writePlyWhole(const std::string& path, const std::string& what, const TriangleMesh& mesh,
                   std::string* error) {
  const auto write = [&](const std::string& temporary, std::string* why) {
    return writePly(temporary, mesh, why);
  };
  return writeThroughTemporary(path, what, write, error);
}

}  // namespace stereo_fusion
