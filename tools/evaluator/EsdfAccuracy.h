#pragma once
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace stereo_fusion {

/// Errors of an ESDF's distances against a reference, by band of the reference distance.
struct EsdfBand {
  double lo_m = 0, hi_m = 0;
  size_t cells = 0;
  double median_m = 0, p99_m = 0, max_m = 0;  ///< of |ESDF − reference|
  double mean_signed_m = 0;   ///< ESDF − reference: > 0 reads farther than the truth
  size_t over_tolerance = 0;  ///< cells whose |error| exceeds the tolerance
};

struct EsdfAccuracy {
  std::vector<EsdfBand> bands;  ///< the bands, then one over everything
  double tolerance_m = 0;
  std::string describe(const std::string& title) const;
};

/// Free cells (distance > 0) of an ESDF point cloud: centres and distances.
struct EsdfCells {
  std::vector<Eigen::Vector3d> free_centres, occupied_centres;
  std::vector<double> free_distances_m;
  /// Per occupied cell, its `centre_sdf` (0 for files without it, written before sub-cell
  /// distances): a free cell's distance is |c − site| − centre_sdf(site).
  std::vector<double> occupied_centre_sdf_m;
};

/// Compares every free cell's distance, capped at `max_distance_m` on both sides, with
/// `reference(centre)`; cells whose reference is beyond the max are left out. Bands end at
/// `band_edges_m` (e.g. 0.25, 0.5, 1, 2).
/// `tolerance_m`: the error counted in EsdfBand::over_tolerance (half a cell for the brute force).
EsdfAccuracy compareEsdf(const EsdfCells& cells, double max_distance_m,
                         const std::vector<double>& band_edges_m,
                         const std::function<double(const Eigen::Vector3d&)>& reference,
                         double tolerance_m);

}  // namespace stereo_fusion
