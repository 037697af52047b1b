#pragma once
// Fixed-bin histogram of absolute depth residuals: the median over hundreds of millions of
// pixels without keeping them.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace stereo_fusion::eval {

/// Counts of |residual| in bins of `kBinWidthM` from 0 to `kRangeM`, plus an overflow bin.
/// Quantiles are exact to one bin (0.1 mm), far below stereo depth noise.
class ResidualHistogram {
 public:
  static constexpr double kBinWidthM = 1e-4;
  static constexpr double kRangeM = 4.0;

  ResidualHistogram();
  void add(double abs_residual_m);
  /// Adds another histogram's counts (integer sums: the order of merging does not matter).
  void merge(const ResidualHistogram& other);
  uint64_t count() const { return count_; }
  /// Value at rank q·(count−1), interpolated inside its bin; kRangeM when it falls in the
  /// overflow bin; NaN when empty.
  double quantile(double q) const;

 private:
  std::vector<uint64_t> bins_;  ///< last bin = overflow
  uint64_t count_ = 0;
};

}  // namespace stereo_fusion::eval
