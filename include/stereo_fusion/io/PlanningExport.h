#pragma once
#include <string>

#include "stereo_fusion/planning/OccupancyGrid2D.h"
#include "stereo_fusion/planning/PlanningMap.h"

namespace stereo_fusion {

/// esdf.ply: one vertex per known planning cell's centre (unknown cells left out), binary
/// little-endian, float x y z, float `distance` (metres, positive in free space, negative
/// inside obstacles, ±esdf_max_distance_m where no obstacle is nearer) and float `centre_sdf`
/// (the TSDF's signed distance at the cell's centre that distances read from it as a site are
/// moved by: PlanningMap::centreSdfM). Via a temporary file.
bool writeEsdfPly(const std::string& path, const PlanningMap& planning, std::string* error);

/// The ROS map_server pair: `pgm_path` (P5, row 0 at the largest y; occupied 0, free 254,
/// unknown 205) and `yaml_path` (image, resolution, origin, negate, thresholds, mode trinary).
bool writeOccupancyMap(const std::string& pgm_path, const std::string& yaml_path,
                       const OccupancyGrid2D& grid, std::string* error);

}  // namespace stereo_fusion
