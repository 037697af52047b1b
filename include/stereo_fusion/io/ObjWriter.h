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
  size_t textured_blocks = 0;      ///< blocks drawn from their texture patch
  size_t vertex_colour_blocks =
      0;  ///< blocks without a patch, drawn from their baked vertex colours
  /// Where each textured block's patch sits in the atlases.
  std::unordered_map<BlockKey, AtlasPlacement, BlockKeyHash> placements;
};

/// Writes `obj_path` (must end in .obj), `<stem>.mtl` and `<stem>_atlas_<K>.png` next to it.
/// One object `block_<x>_<y>_<z>` per submesh, in key order, vertices not welded across blocks.
/// Every face has texture coordinates into atlas `K` (material `atlas_<K>`, map_Kd the PNG;
/// OBJ convention: v up): blocks with a patch use their patch UVs remapped into the atlas,
/// blocks without one get their vertex colours baked (bakeVertexColours), because viewers
/// show a textured material's map, not vertex colours, and Open3D drops every UV of a file
/// in which some faces have none. Vertices also carry their colour (`v x y z r g b`, r, g, b
/// in [0, 1]). Returns false with a message naming the file on failure.
bool writeTexturedObj(const std::string& obj_path,
                      const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                      const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>& patches,
                      const ObjExportOptions& options, ObjExportInfo* info, std::string* error);

/// The vertex colours of `mesh` as a texture: triangle t gets a 2×2 texel tile holding its
/// corner colours c0, c1, c2 and c1 + c2 − c0 (clamped), so bilinear sampling between the
/// three texel centres reproduces the barycentric vertex-colour blend exactly (unless clamped).
/// `corner_uvs` receives 3 UVs per triangle (TexturePatch convention), in triangle order.
cv::Mat bakeVertexColours(const SubMesh& mesh, std::vector<Eigen::Vector2f>* corner_uvs);

}  // namespace stereo_fusion
