#pragma once
// What ~mesh_markers has not drawn yet: the mesh's changes between two marker publishes,
// merged, so rviz can be fed at a lower rate than ~mesh_update without missing a block.
#include <algorithm>
#include <set>
#include <vector>

#include "stereo_fusion/map/BlockKey.h"

namespace stereo_fusion {

class MarkerBacklog {
 public:
  /// One flush of mesh changes, in order: a block changed after it was removed is drawn again,
  /// one removed after it changed is only deleted.
  void add(const std::vector<BlockKey>& changed, const std::vector<BlockKey>& removed) {
    for (const BlockKey& key : changed) {
      removed_.erase(key);
      changed_.insert(key);
    }
    for (const BlockKey& key : removed) {
      changed_.erase(key);
      removed_.insert(key);
    }
  }
  bool empty() const { return changed_.empty() && removed_.empty(); }
  /// The merged changes, sorted by key, and an empty backlog.
  void take(std::vector<BlockKey>* changed, std::vector<BlockKey>* removed) {
    changed->assign(changed_.begin(), changed_.end());
    removed->assign(removed_.begin(), removed_.end());
    clear();
  }
  void clear() {
    changed_.clear();
    removed_.clear();
  }

 private:
  std::set<BlockKey> changed_, removed_;
};

}  // namespace stereo_fusion
