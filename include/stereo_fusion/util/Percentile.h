#pragma once
#include <algorithm>
#include <cstddef>
#include <vector>

namespace stereo_fusion {

/// Nearest-rank percentile (p in [0, 1]) of already sorted values; 0 when empty.
inline double percentileOfSorted(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0.0;
  return sorted[std::min(sorted.size() - 1, static_cast<size_t>(p * (sorted.size() - 1) + 0.5))];
}

/// Nearest-rank percentile of unsorted values (sorts a copy).
inline double percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  return percentileOfSorted(values, p);
}

}  // namespace stereo_fusion
