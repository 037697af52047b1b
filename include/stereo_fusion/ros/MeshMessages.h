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

/// One submesh as a MeshBlock message, with its texture patch (PNG) and UVs when `patch` is
/// given and matches the submesh.
MeshBlock toMeshBlock(const SubMesh& submesh, const TexturePatch* patch = nullptr);

/// A MeshUpdate with the submeshes of `changed` (taken from `store`) and the `removed` keys;
/// textured blocks carry their patch when `textures` is given.
MeshUpdate toMeshUpdate(const MeshStore& store, const std::vector<BlockKey>& changed,
                        const std::vector<BlockKey>& removed, const std_msgs::Header& header,
                        double voxel_size_m, uint64_t sequence, bool full,
                        const TextureStore* textures = nullptr);

/// Applies `update` to `mesh` (key → submesh), as a subscriber would. Returns false when a
/// message is malformed (index out of range, array sizes that do not match, UVs without a
/// texture or outside [0, 1]). With `textures`, the blocks' patches are decoded into it too
/// (image and UVs only; a block without UVs loses its patch).
bool applyMeshUpdate(const MeshUpdate& update, std::unordered_map<BlockKey, SubMesh, BlockKeyHash>* mesh,
                     std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* textures = nullptr);

/// rviz markers for the changed blocks (one vertex-coloured TRIANGLE_LIST per block, namespace
/// "mesh", a stable id per block) and DELETE markers for the removed ones.
class MeshMarkers {
 public:
  visualization_msgs::MarkerArray build(const MeshStore& store, const std::vector<BlockKey>& changed,
                                        const std::vector<BlockKey>& removed, const std_msgs::Header& header);
  /// A DELETEALL marker, and forget every id (after ~reset).
  visualization_msgs::MarkerArray clear(const std_msgs::Header& header);

 private:
  int idOf(const BlockKey& key);
  std::unordered_map<BlockKey, int, BlockKeyHash> ids_;
  int next_id_ = 0;
};

}  // namespace stereo_fusion
