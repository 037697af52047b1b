#pragma once
// How well a 2D occupancy map marks the true obstacles of its height band: are its occupied
// pixels on a true surface (precision), and are the true walls and obstacles it saw occupied
// (recall).

#include <string>
#include <utility>
#include <vector>

#include "evaluator/OccupancyMapFile.h"
#include "evaluator/SolidTruth.h"
#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion::eval {

struct OccupancyScoreOptions {
  /// The map's height band (world z): the mapper's grid_min_z_m / grid_max_z_m (defaults 0.1,
  /// 1.5 m). Only true surface in the band counts.
  double min_z_m = 0.1, max_z_m = 1.5;
  /// How far (horizontally) a pixel may lie from what makes it right: about a cell, so a wall
  /// drawn in the neighbouring column still counts.
  double reach_m = 0.10;
  /// The true surface is sampled on a grid of at most this edge on every triangle.
  double sample_step_m = 0.02;
  /// Triangles whose unit normal has |n_z| below this are walls or obstacles; above it they
  /// are floors, ceilings and table tops, which the recall leaves out (a planner drives under
  /// or over them at the band's edges; precision still accepts them).
  double wall_max_abs_normal_z = 0.7;
};

struct OccupancyScore {
  OccupancyScoreOptions options;
  /// Precision: occupied pixels with a true surface point (z in the band) within reach_m of the
  /// pixel's square, horizontally, or (given the solids) whose centre's column lies inside a
  /// solid somewhere in the band: behind a wall is an obstacle too, not a false one.
  size_t occupied_pixels = 0, occupied_on_surface = 0;
  /// Recall: "obstacle pixels" hold a wall point (z in the band) in their square, in the map's
  /// pixel lattice (extended past its edges). Those with a known pixel within reach_m (squares'
  /// gap) count; found = with an occupied pixel within reach_m. Unseen walls are left out: they
  /// are coverage, not the map's mistakes.
  size_t obstacle_pixels_known = 0, obstacle_pixels_found = 0;
  size_t obstacle_pixels_unknown = 0;  ///< no known pixel within reach_m (not scored)
  /// The occupied pixels precision does not accept (map column x, row y; row 0 at the
  /// smallest y): where a picture marks the false obstacles.
  std::vector<std::pair<int, int>> false_pixels;

  double precision() const;
  double wallRecall() const;
  /// One line; `band_from` says where the band came from (e.g. "stats.json").
  std::string describe(const std::string& name, const std::string& band_from) const;
};

/// Scores `map` against the true surface `truth` (any winding: only where the surface is);
/// `solid` (optional: `truth` read as solids) also accepts occupied pixels inside a solid.
OccupancyScore scoreOccupancy(const OccupancyMap& map, const TriangleMesh& truth,
                              const OccupancyScoreOptions& options = {},
                              const SolidTruth* solid = nullptr);

}  // namespace stereo_fusion::eval
