#include "evaluator/DistanceStats.h"

#include <algorithm>
#include <cmath>

namespace stereo_fusion::eval {
namespace {

/// Value at rank q·(n−1) of an ascending list, interpolated between neighbours.
double quantileOfSorted(const std::vector<double>& sorted, double q) {
  const double rank = q * static_cast<double>(sorted.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(rank));
  const size_t above = std::min(below + 1, sorted.size() - 1);
  const double weight = rank - static_cast<double>(below);
  return sorted[below] + weight * (sorted[above] - sorted[below]);
}

}  // namespace

DistanceSummary summarizeDistances(std::vector<double> distances_m) {
  DistanceSummary summary;
  summary.count = distances_m.size();
  if (distances_m.empty()) return summary;
  std::sort(distances_m.begin(), distances_m.end());
  double sum = 0.0;
  for (const double d : distances_m) sum += d;
  summary.mean_m = sum / static_cast<double>(distances_m.size());
  summary.median_m = quantileOfSorted(distances_m, 0.5);
  summary.p90_m = quantileOfSorted(distances_m, 0.9);
  summary.p99_m = quantileOfSorted(distances_m, 0.99);
  summary.max_m = distances_m.back();
  const auto first_over = std::upper_bound(distances_m.begin(), distances_m.end(), kGrossErrorM);
  summary.share_over_10cm =
      static_cast<double>(distances_m.end() - first_over) / static_cast<double>(distances_m.size());
  return summary;
}

double shareWithin(const std::vector<double>& distances_m, double tolerance_m) {
  if (distances_m.empty()) return NAN;
  const size_t within =
      static_cast<size_t>(std::count_if(distances_m.begin(), distances_m.end(),
                                        [tolerance_m](double d) { return d <= tolerance_m; }));
  return static_cast<double>(within) / static_cast<double>(distances_m.size());
}

double fScore(double precision, double recall) {
  if (!(precision + recall > 0.0)) return 0.0;  // also NaN
  return 2.0 * precision * recall / (precision + recall);
}

}  // namespace stereo_fusion::eval
