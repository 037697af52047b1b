#include "stereo_fusion/io/PlyWriter.h"

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
  // One buffer per element keeps the write fast; x86 and ARM are little-endian like the file.
  constexpr size_t kVertexBytes = 6 * 4 + 3;
  std::vector<char> buffer(mesh.positions.size() * kVertexBytes);
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    char* p = buffer.data() + v * kVertexBytes;
    std::memcpy(p, mesh.positions[v].data(), 12);
    std::memcpy(p + 12, mesh.normals[v].data(), 12);
    std::memcpy(p + 24, mesh.colors[v].data(), 3);
  }
  out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  constexpr size_t kFaceBytes = 1 + 3 * 4;
  buffer.assign(mesh.triangles.size() * kFaceBytes, 0);
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    char* p = buffer.data() + f * kFaceBytes;
    p[0] = 3;
    for (int k = 0; k < 3; ++k) {
      const int32_t index = static_cast<int32_t>(mesh.triangles[f][k]);
      std::memcpy(p + 1 + 4 * k, &index, 4);
    }
  }
  out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  if (!out) {
    *error = path + ": write failed (disk full?)";
    return false;
  }
  return true;
}

}  // namespace stereo_fusion
