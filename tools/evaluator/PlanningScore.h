#pragma once
// What an ESDF's errors mean to a planner, against the true surface read as solids: how far free
// cells near surfaces are off, occupied cells that float in free space, and free cells that lie
// inside a solid.

#include <Eigen/Core>
#include <vector>
#include <functional>
#include <string>

#include "evaluator/EsdfAccuracy.h"

namespace stereo_fusion {

/// The thresholds of the planning report.
struct PlanningScoreOptions {
  /// Free cells whose true distance lies in [near_lo_m, near_hi_m]: the space a planner threads
  /// through near surfaces (farther cells are clamped by the ESDF's max anyway).
  double near_lo_m = 0.1, near_hi_m = 1.5;
  /// A near cell whose ESDF distance is this much below the truth is "too close": a planner
  /// keeps away from obstacles that are not there.
  double too_close_m = 0.10;
  /// An occupied cell whose centre lies at least this far into free space is a phantom.
  double phantom_m = 0.12;
  /// Free cells whose ESDF distance is at least this are checked for lying inside a solid: a
  /// planner would route through them.
  double clear_min_m = 0.2;
};

struct PlanningScore {
  PlanningScoreOptions options;
  double max_distance_m = 0.0;
  // Free cells near a surface: |min(ESDF, max) − truth|.
  size_t near_cells = 0;
  double near_median_m = 0.0, near_p90_m = 0.0;
  size_t near_too_close = 0;  ///< ESDF more than too_close_m below the truth
  /// The near cells whose nearest true surface point the map saw (scorePlanning's
  /// `nearest_seen`): what the ESDF gets wrong where it could know; the others read the nearest
  /// surface the map has, up to metres past an unseen one.
  size_t near_seen_cells = 0;
  double near_seen_median_m = 0.0, near_seen_p90_m = 0.0;
  // Occupied cells in free space.
  size_t occupied_cells = 0, phantom_cells = 0;
  double phantom_median_distance_m = 0.0, phantom_median_z_m = 0.0;
  std::vector<Eigen::Vector3d> phantom_centres;  ///< where a picture marks them
  // Free cells the ESDF calls clear that lie inside a solid.
  size_t clear_cells = 0, clear_inside_solid = 0;

  std::string describe() const;
};

/// `a` / `b`, 0 when `b` is 0.
inline double shareOf(size_t a, size_t b) { return b == 0 ? 0.0 : double(a) / double(b); }

/// Scores every cell of `cells` against `signed_truth(centre)` (metres, negative inside a solid,
/// e.g. eval::SolidTruth). ESDF distances are capped at `max_distance_m`; near cells whose truth
/// exceeds it are left out (the ESDF cannot tell them apart). Percentiles are nearest-rank.
/// `nearest_seen(centre)`, if given, says whether a free cell's nearest true surface point was
/// seen (near_seen_*); without it those stay 0.
PlanningScore scorePlanning(const EsdfCells& cells, double max_distance_m,
                            const std::function<double(const Eigen::Vector3d&)>& signed_truth,
                            const PlanningScoreOptions& options = {},
                            const std::function<bool(const Eigen::Vector3d&)>& nearest_seen = {});

}  // namespace stereo_fusion
