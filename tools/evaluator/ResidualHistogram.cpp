#include "evaluator/ResidualHistogram.h"

#include <cmath>

namespace stereo_fusion::eval {

ResidualHistogram::ResidualHistogram()
    : bins_(static_cast<size_t>(std::lround(kRangeM / kBinWidthM)) + 1, 0) {}

void ResidualHistogram::add(double abs_residual_m) {
  const double bin = std::floor(abs_residual_m / kBinWidthM);
  const size_t overflow = bins_.size() - 1;
  // NaN and anything past the range land in the overflow bin.
  const size_t index =
      bin >= 0.0 && bin < static_cast<double>(overflow) ? static_cast<size_t>(bin) : overflow;
  ++bins_[index];
  ++count_;
}

void ResidualHistogram::merge(const ResidualHistogram& other) {
  for (size_t i = 0; i < bins_.size(); ++i) bins_[i] += other.bins_[i];
  count_ += other.count_;
}

double ResidualHistogram::quantile(double q) const {
  if (count_ == 0) return NAN;
  const double rank = q * static_cast<double>(count_ - 1);
  uint64_t before = 0;
  for (size_t i = 0; i < bins_.size(); ++i) {
    if (bins_[i] == 0) continue;
    if (rank < static_cast<double>(before + bins_[i])) {
      if (i + 1 == bins_.size()) return kRangeM;
      // Spread the bin's samples evenly over its width (centres of equal sub-intervals).
      const double within =
          (rank - static_cast<double>(before) + 0.5) / static_cast<double>(bins_[i]);
      return (static_cast<double>(i) + within) * kBinWidthM;
    }
    before += bins_[i];
  }
  return kRangeM;
}

}  // namespace stereo_fusion::eval
