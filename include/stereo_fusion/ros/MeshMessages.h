#pragma once
#include <stereo_fusion/MeshBlock.h>
#include <stereo_fusion/MeshUpdate.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <unordered_map>
#include <vector>

#include "stereo_fusion/mesh/MeshStore.h"

namespace stereo_fusion {

/// One submesh as a MeshBlock message.
MeshBlock toMeshBlock(const SubMesh& submesh);

/// A MeshUpdate with the submeshes of `changed` (taken from `store`) and the `removed` keys.
MeshUpdate toMeshUpdate(const MeshStore& store, const std::vector<BlockKey>& changed,
                        const std::vector<BlockKey>& removed, const std_msgs::Header& header,
                        double voxel_size_m, uint64_t sequence, bool full);

/// Applies `update` to `mesh` (key → submesh), as a subscriber would. Returns false when a
/// message is malformed (index out of range, array sizes that do not match).
bool applyMeshUpdate(const MeshUpdate& update, std::unordered_map<BlockKey, SubMesh, BlockKeyHash>* mesh);

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
