#include "stereo_fusion/io/MeshExport.h"

#include <filesystem>

#include "stereo_fusion/io/ObjWriter.h"
#include "stereo_fusion/io/PlyWriter.h"
#include "stereo_fusion/mesh/MeshStore.h"

namespace stereo_fusion {

bool exportMesh(const std::string& path,
                const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>& patches,
                std::string* message) {
  if (std::filesystem::path(path).extension() == ".obj") {
    ObjExportInfo info;
    if (!writeTexturedObj(path, submeshes, patches, ObjExportOptions{}, &info, message))
      return false;
    *message = "wrote " + std::to_string(info.textured_blocks) + " textured and " +
               std::to_string(info.vertex_colour_blocks) + " vertex-coloured blocks to " + path;
    return true;
  }
  const TriangleMesh mesh = weldSubmeshes(submeshes);
  if (!writePlyWhole(path, "mesh", mesh, message)) return false;
  *message = "wrote " + std::to_string(mesh.triangles.size()) + " triangles to " + path;
  return true;
}

}  // namespace stereo_fusion
