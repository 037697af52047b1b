#pragma once
#include <cstddef>
#include <vector>

#include "stereo_fusion/Mapper.h"

namespace stereo_fusion {

/// A subscriber of the mesh's changes, as the session knows it: it stays valid when a
/// correction swaps in a new Mapper (the session subscribes it there again).
enum class MeshSubscription : size_t {};

/// The live map as the session lends it for one call, its map lock held (MappingSession::
/// withMap(), the MapReplaced listener): read it, and bring what is derived from the TSDF up to
/// date — the mesh, the planning layer — or take a subscriber's mesh changes. Whatever writes
/// the TSDF (frames, clears, reset, load, a correction) goes through the session's own
/// operations, and no reference outlives the call: none can point to a map a correction replaced.
class MapAccess {
 public:
  const Mapper& map() const { return *mapper_; }
  /// Meshes what fusion changed since the last pass (Mapper::updateMesh()).
  MeshPass updateMesh() { return mapper_->updateMesh(); }
  /// Brings the planning layer up to date, all of it under the map lock (Mapper::updatePlanning()).
  PlanningPass updatePlanning() { return mapper_->updatePlanning(); }
  /// Recomputes the planning layer from the TSDF (Mapper::rebuildPlanning()).
  PlanningPass rebuildPlanning() { return mapper_->rebuildPlanning(); }
  /// The changes `subscriber` has not taken yet, taken (Mapper::takeMeshChanges()).
  BlockChangeLog::Changes takeMeshChanges(MeshSubscription subscriber) {
    return mapper_->takeMeshChanges(consumer(subscriber));
  }
  size_t pendingMeshChanges(MeshSubscription subscriber) const {
    return mapper_->pendingMeshChanges(consumer(subscriber));
  }

 private:
  friend class MappingSession;
  MapAccess(Mapper* mapper, const std::vector<BlockChangeLog::Consumer>* consumers)
      : mapper_(mapper), consumers_(consumers) {}
  BlockChangeLog::Consumer consumer(MeshSubscription subscriber) const {
    return (*consumers_)[static_cast<size_t>(subscriber)];
  }
  Mapper* mapper_;
  const std::vector<BlockChangeLog::Consumer>* consumers_;
};

}  // namespace stereo_fusion
