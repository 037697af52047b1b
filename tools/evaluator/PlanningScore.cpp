#include "evaluator/PlanningScore.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "stereo_fusion/util/Percentile.h"

namespace stereo_fusion {

PlanningScore scorePlanning(const EsdfCells& cells, double max_distance_m,
                            const std::function<double(const Eigen::Vector3d&)>& signed_truth,
                            const PlanningScoreOptions& options,
                            const std::function<bool(const Eigen::Vector3d&)>& nearest_seen) {
  PlanningScore score;
  score.options = options;
  score.max_distance_m = max_distance_m;
  std::vector<double> near_errors, near_seen_errors;
  for (size_t i = 0; i < cells.free_centres.size(); ++i) {
    const double truth = signed_truth(cells.free_centres[i]);
    const double esdf = cells.free_distances_m[i];
    if (esdf >= options.clear_min_m) {
      ++score.clear_cells;
      score.clear_inside_solid += truth < 0.0;
    }
    if (!(truth >= options.near_lo_m && truth <= options.near_hi_m && truth <= max_distance_m))
      continue;
    const double capped = std::min(esdf, max_distance_m);
    near_errors.push_back(std::abs(capped - truth));
    if (nearest_seen && nearest_seen(cells.free_centres[i]))
      near_seen_errors.push_back(near_errors.back());
    score.near_too_close += capped < truth - options.too_close_m;
  }
  score.near_cells = near_errors.size();
  std::sort(near_errors.begin(), near_errors.end());
  score.near_median_m = percentileOfSorted(near_errors, 0.5);
  score.near_p90_m = percentileOfSorted(near_errors, 0.9);
  score.near_seen_cells = near_seen_errors.size();
  std::sort(near_seen_errors.begin(), near_seen_errors.end());
  score.near_seen_median_m = percentileOfSorted(near_seen_errors, 0.5);
  score.near_seen_p90_m = percentileOfSorted(near_seen_errors, 0.9);

  std::vector<double> phantom_distances, phantom_z;
  for (const Eigen::Vector3d& centre : cells.occupied_centres) {
    const double truth = signed_truth(centre);
    if (std::isfinite(truth) && truth >= options.phantom_m) {
      phantom_distances.push_back(truth);
      phantom_z.push_back(centre.z());
      score.phantom_centres.push_back(centre);
    }
  }
  score.occupied_cells = cells.occupied_centres.size();
  score.phantom_cells = phantom_distances.size();
  score.phantom_median_distance_m = percentile(phantom_distances, 0.5);
  score.phantom_median_z_m = percentile(phantom_z, 0.5);
  return score;
}

std::string PlanningScore::describe() const {
  const PlanningScoreOptions& o = options;
  char text[768];
  std::snprintf(
      text, sizeof(text),
      "planning (solid truth): free %.1f-%.1f m: %zu cells, median %.1f cm, p90 %.1f cm, "
      ">%.0f cm too close %.1f %% (%zu)\n"
      "  phantom occupied (>= %.0f cm in free space): %zu of %zu (%.1f %%), median distance "
      "%.3f m, median z %.2f m\n"
      "  free >= %.1f m inside a solid: %zu of %zu (%.1f %%)\n",
      o.near_lo_m, std::min(o.near_hi_m, max_distance_m), near_cells, 100.0 * near_median_m,
      100.0 * near_p90_m, 100.0 * o.too_close_m, 100.0 * shareOf(near_too_close, near_cells),
      near_too_close, 100.0 * o.phantom_m, phantom_cells, occupied_cells,
      100.0 * shareOf(phantom_cells, occupied_cells), phantom_median_distance_m, phantom_median_z_m,
      o.clear_min_m, clear_inside_solid, clear_cells,
      100.0 * shareOf(clear_inside_solid, clear_cells));
  std::string out = text;
  if (near_seen_cells > 0) {
    std::snprintf(text, sizeof(text),
                  "  free %.1f-%.1f m whose nearest true surface was seen: %zu cells (%.1f %%), "
                  "median %.1f cm, p90 %.1f cm\n",
                  o.near_lo_m, std::min(o.near_hi_m, max_distance_m), near_seen_cells,
                  100.0 * shareOf(near_seen_cells, near_cells), 100.0 * near_seen_median_m,
                  100.0 * near_seen_p90_m);
    out += text;
  }
  return out;
}

}  // namespace stereo_fusion
