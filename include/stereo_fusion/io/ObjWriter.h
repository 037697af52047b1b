#pragma once
// Textured mesh export: Wavefront OBJ + MTL + atlas PNGs (thesis §3.6 method B).

#include <string>
#include <unordered_map>
#include <vector>

#include "stereo_fusion/io/TextureAtlas.h"
#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/mesh/TexturePatch.h"

namespace stereo_fusion {

/// Atlas layout of the export.
struct ObjExportOptions {
  int atlas_edge_px = 4096;  ///< atlas width (and maximum height); common GPU texture limit
  int gutter_px = 2;         ///< replicated border around every patch in the atlas
};

/// What writeTexturedObj() wrote.
struct ObjExportInfo {
  std::vector<std::string> files;  ///< the .obj, the .mtl and every atlas PNG, full paths
  size_t textured_blocks = 0;      ///< blocks drawn from a patch (material atlas_K)
  size_t vertex_colour_blocks = 0; ///< blocks without a patch (material vertex_colour)
  /// Where each textured block's patch sits in the atlases.
  std::unordered_map<BlockKey, AtlasPlacement, BlockKeyHash> placements;
};

/// Writes `obj_path` (must end in .obj), `<stem>.mtl` and `<stem>_atlas_<K>.png` next to it.
/// One object `block_<x>_<y>_<z>` per submesh, in key order, vertices not welded across blocks.
/// Every vertex carries its colour as `v x y z r g b` (r, g, b in [0, 1], read by MeshLab,
/// Blender and Open3D), so blocks without a patch keep their vertex colour; textured blocks
/// use material `atlas_<K>` whose map_Kd is the atlas PNG, with their UVs remapped into the
/// atlas (OBJ convention: v up). Returns false with a message naming the file on failure.
bool writeTexturedObj(const std::string& obj_path,
                      const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                      const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>& patches,
                      const ObjExportOptions& options, ObjExportInfo* info, std::string* error);

}  // namespace stereo_fusion
