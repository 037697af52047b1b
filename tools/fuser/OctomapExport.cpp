#include "fuser/OctomapExport.h"

#include <octomap/OcTree.h>

#include "stereo_fusion/io/WriteTarget.h"

namespace stereo_fusion {

bool writeOctomap(const std::string& path, const PlanningMap& planning, size_t* skipped,
                  std::string* error) {
  octomap::OcTree tree(planning.grid().cell_m);
  size_t outside = 0;
  planning.forEachKnownCell([&](const CellIndex& cell, CellState state, double) {
    const Eigen::Vector3d p = planning.grid().centre(cell);
    octomap::OcTreeKey key;
    if (!tree.coordToKeyChecked(octomap::point3d(p.x(), p.y(), p.z()), key)) {
      ++outside;
      return;
    }
    octomap::OcTreeNode* node =
        tree.updateNode(key, state == CellState::kOccupied, /*lazy_eval=*/true);
    node->setLogOdds(state == CellState::kOccupied ? tree.getClampingThresMaxLog()
                                                   : tree.getClampingThresMinLog());
  });
  tree.updateInnerOccupancy();
  tree.prune();
  if (skipped) *skipped = outside;
  return writeThroughTemporary(
      path, "octomap",
      [&](const std::string& temporary, std::string* e) {
        if (tree.writeBinary(temporary)) return true;
        *e = temporary + ": octomap write failed";
        return false;
      },
      error);
}

}  // namespace stereo_fusion
