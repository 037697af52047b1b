#pragma once
// Summaries of distance lists: mean, median, 90th and 99th percentiles, share within a
// tolerance, share of gross errors.

#include <cmath>
#include <cstddef>
#include <vector>

namespace stereo_fusion::eval {

/// The threshold of `share_over_10cm`: a gross error at every voxel size we run (1–4 cm),
/// whatever the tolerance, so the share compares across runs.
constexpr double kGrossErrorM = 0.10;

/// Summary of a list of distances (metres). All fields are NaN when `count` is 0.
struct DistanceSummary {
  size_t count = 0;
  double mean_m = NAN;
  double median_m = NAN;
  double p90_m = NAN;
  double p99_m = NAN;
  double max_m = NAN;
  double share_over_10cm = NAN;  ///< fraction of distances > kGrossErrorM
};

/// Mean, median (50th percentile), 90th and 99th percentiles, maximum and the share over
/// kGrossErrorM. Percentiles interpolate linearly between order statistics (value at rank
/// q·(n−1)), so the median of {1, 2} is 1.5.
DistanceSummary summarizeDistances(std::vector<double> distances_m);

/// Share of `distances_m` that are ≤ `tolerance_m`, in [0, 1]; NaN for an empty list.
double shareWithin(const std::vector<double>& distances_m, double tolerance_m);

/// F-score 2PR/(P+R): the harmonic mean of precision and recall (completeness); 0 when both are
/// 0 or either is NaN (a missing mesh has no F-score worth averaging).
double fScore(double precision, double recall);

}  // namespace stereo_fusion::eval
