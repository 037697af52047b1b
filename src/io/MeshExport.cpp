#include "stereo_fusion/io/MeshExport.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "stereo_fusion/io/ObjWriter.h"
#include "stereo_fusion/io/PlyWriter.h"
#include "stereo_fusion/io/WriteTarget.h"
#include "stereo_fusion/mesh/MeshStore.h"

namespace stereo_fusion {

bool exportMesh(const std::string& path, const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>& patches, std::string* message) {
  if (std::filesystem::path(path).extension() == ".obj") {
    ObjExportInfo info;
    if (!writeTexturedObj(path, submeshes, patches, ObjExportOptions{}, &info, message)) return false;
    *message = "wrote " + std::to_string(info.textured_blocks) + " textured and " +
               std::to_string(info.vertex_colour_blocks) + " vertex-coloured blocks to " + path;
    return true;
  }
  if (!isWritableTarget(path, message)) return false;
  const TriangleMesh mesh = weldSubmeshes(submeshes);
  // Through a temporary and a rename: a reader never sees half a mesh, a failed write leaves
  // the old file.
  const std::string tmp = temporaryPathBeside(path);
  if (!writePly(tmp, mesh, message)) {
    std::remove(tmp.c_str());
    return false;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    *message = path + ": cannot write the mesh (rename failed: " + std::strerror(errno) + ")";
    std::remove(tmp.c_str());
    return false;
  }
  *message = "wrote " + std::to_string(mesh.triangles.size()) + " triangles to " + path;
  return true;
}

}  // namespace stereo_fusion
