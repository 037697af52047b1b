#pragma once
#include <stereo_fusion/MeshBlock.h>
#include <stereo_fusion/MeshUpdate.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <unordered_map>
#include <vector>

#include "stereo_fusion/mesh/MeshStore.h"
#include "stereo_fusion/mesh/TextureStore.h"

namespace stereo_fusion {

/// How MeshBlock carries positions, normals and triangles (see msg/MeshBlock.msg).
enum class MeshEncoding {
  kFloat32,  ///< float32 positions and normals, uint32 indices: exact
  kCompact,  ///< uint16 positions relative to the block origin, int8 normals, uint16 indices
};

/// "float32" | "compact" → encoding; false for anything else.
bool parseMeshEncoding(const std::string& text, MeshEncoding* encoding);

/// Metres per unit of MeshBlock::vertices_q for blocks of `block_size_m`.
inline double compactPositionStep(double block_size_m) { return block_size_m / 32768.0; }

/// One submesh as a MeshBlock message. kCompact falls back to float32 for a block whose
/// vertices do not fit the quantisation (see msg/MeshBlock.msg). With `patch` (matching the
/// submesh) the block carries its texture patch (PNG) and UVs.
MeshBlock toMeshBlock(const SubMesh& submesh, MeshEncoding encoding = MeshEncoding::kFloat32,
                      double block_size_m = 0.0, const TexturePatch* patch = nullptr);

/// A MeshUpdate with the submeshes of `changed` (taken from `submeshes`) and the `removed` keys;
/// textured blocks carry their patch when `textures` is given. `session` stays 0: the
/// publisher sets it.
MeshUpdate toMeshUpdate(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                        const std::vector<BlockKey>& changed, const std::vector<BlockKey>& removed,
                        const std_msgs::Header& header, double voxel_size_m, uint64_t sequence,
                        bool full, MeshEncoding encoding = MeshEncoding::kFloat32,
                        const TextureStore* textures = nullptr);

/// The same with the patches as a plain key → patch map (a subscriber such as MeshAssembler
/// holds what applyMeshUpdate decoded, not a TextureStore); null = no textures.
MeshUpdate toMeshUpdate(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                        const std::vector<BlockKey>& changed, const std::vector<BlockKey>& removed,
                        const std_msgs::Header& header, double voxel_size_m, uint64_t sequence,
                        bool full, MeshEncoding encoding,
                        const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* patches);

/// Applies `update` to `mesh` (key → submesh), as a subscriber would; decodes both encodings.
/// Returns false when a message is malformed (index out of range, array sizes that do not
/// match, UVs without a texture or outside [0, 1], a non-finite block_size, a level above 2, a
/// texture that is not a PNG or declares more than 1024 px per edge in its header) and then
/// leaves `mesh` and `textures` untouched. With
/// `textures`, the blocks' patches are decoded into it too (image and UVs only; a block
/// without UVs loses its patch).
bool applyMeshUpdate(const MeshUpdate& update,
                     std::unordered_map<BlockKey, SubMesh, BlockKeyHash>* mesh,
                     std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* textures = nullptr);

/// rviz markers for the changed blocks (one vertex-coloured TRIANGLE_LIST per block, namespace
/// "mesh", a stable id per block) and DELETE markers for the removed ones.
class MeshMarkers {
 public:
  visualization_msgs::MarkerArray build(
      const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
      const std::vector<BlockKey>& changed, const std::vector<BlockKey>& removed,
      const std_msgs::Header& header);
  /// A DELETEALL marker, and forget every id (after ~reset).
  visualization_msgs::MarkerArray clear(const std_msgs::Header& header);
  /// Blocks that currently have a marker id (drawn and not deleted since).
  size_t size() const { return ids_.size(); }

 private:
  int idOf(const BlockKey& key);
  std::unordered_map<BlockKey, int, BlockKeyHash> ids_;
  int next_id_ = 0;
};

}  // namespace stereo_fusion
