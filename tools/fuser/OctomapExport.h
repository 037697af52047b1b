#pragma once
#include <string>

#include "stereo_fusion/planning/PlanningMap.h"

namespace stereo_fusion {

/// octomap.bt: the planning layer as an OctoMap OcTree (liboctomap) at the planning cell size,
/// whose voxels coincide with the cells (both grids are floor(p / resolution)): occupied cells
/// at the occupancy clamping maximum, free ones at its minimum, unknown ones absent; pruned and
/// written with OcTree::writeBinary() (what octomap_server, MoveIt and octovis read). Cells
/// beyond OctoMap's ±2¹⁵-cell range are left out and counted in `*skipped`.
bool writeOctomap(const std::string& path, const PlanningMap& planning, size_t* skipped,
                  std::string* error);

}  // namespace stereo_fusion
