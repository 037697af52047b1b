#include "evaluator/EsdfDelta.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>
#include <unordered_map>

namespace stereo_fusion::eval {

namespace {
struct KeyHash {
  size_t operator()(const std::tuple<int64_t, int64_t, int64_t>& k) const {
    return static_cast<size_t>(std::get<0>(k) * 73856093 ^ std::get<1>(k) * 19349663 ^
                               std::get<2>(k) * 83492791);
  }
};
/// The cell a centre names: centres lie at (i + 0.5)·cell, so the rounded quotient is exact.
std::tuple<int64_t, int64_t, int64_t> keyOf(const Eigen::Vector3d& centre, double cell_m) {
  return {std::llround(centre.x() / cell_m - 0.5), std::llround(centre.y() / cell_m - 0.5),
          std::llround(centre.z() / cell_m - 0.5)};
}
}  // namespace

CellDelta compareWithBefore(const EsdfCells& now, const EsdfCells& before, double max_distance_m,
                            double cell_m,
                            const std::function<double(const Eigen::Vector3d&)>& signed_truth) {
  CellDelta delta;
  delta.cell_m = cell_m;
  delta.now_cells = now.free_centres.size();
  std::unordered_map<std::tuple<int64_t, int64_t, int64_t>, double, KeyHash> earlier;
  for (size_t i = 0; i < before.free_centres.size(); ++i)
    earlier[keyOf(before.free_centres[i], cell_m)] = before.free_distances_m[i];
  std::unordered_map<std::tuple<int64_t, int64_t, int64_t>, bool, KeyHash> free_now;
  for (size_t i = 0; i < now.free_centres.size(); ++i) {
    const auto key = keyOf(now.free_centres[i], cell_m);
    free_now[key] = true;
    const auto it = earlier.find(key);
    if (it == earlier.end()) continue;
    ++delta.both_free;
    const double truth = std::min(signed_truth(now.free_centres[i]), max_distance_m);
    const double error_now = std::abs(std::min(now.free_distances_m[i], max_distance_m) - truth);
    const double error_before = std::abs(std::min(it->second, max_distance_m) - truth);
    const double growth = error_now - error_before;
    delta.worst_growth_m = std::max(delta.worst_growth_m, growth);
    // A millimetre over half a cell: sub-cell distances move a cell by up to half a cell, and
    // float rounding must not count that as more.
    delta.worse += growth > 0.5 * cell_m + 1e-3;
    delta.better += growth < -0.5 * cell_m - 1e-3;
  }
  for (const auto& [key, distance] : earlier) delta.lost_free += !free_now.count(key);
  return delta;
}

std::string CellDelta::describe(const std::string& before_path) const {
  char line[512];
  std::snprintf(line, sizeof(line),
                "against %s: %zu cells free in both; |error| grew by over half a cell (%.1f cm) "
                "in %zu (%.2f %%), shrank by as much in %zu (%.2f %%); largest growth %.1f cm; "
                "%zu free before are not now\n",
                before_path.c_str(), both_free, 50.0 * cell_m, worse,
                both_free ? 100.0 * worse / both_free : 0.0, better,
                both_free ? 100.0 * better / both_free : 0.0, 100.0 * worst_growth_m, lost_free);
  return line;
}

nlohmann::ordered_json toJson(const CellDelta& d, const std::string& before_path) {
  return {{"before", before_path},
          {"cell_m", d.cell_m},
          {"free_cells", d.now_cells},
          {"free_in_both", d.both_free},
          {"worse", d.worse},
          {"better", d.better},
          {"worst_growth_m", d.worst_growth_m},
          {"lost_free", d.lost_free}};
}

}  // namespace stereo_fusion::eval
