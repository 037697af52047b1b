#include "evaluator/EsdfAccuracy.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "stereo_fusion/util/Percentile.h"

namespace stereo_fusion {

EsdfAccuracy compareEsdf(const EsdfCells& cells, double max_distance_m,
                         const std::vector<double>& band_edges_m,
                         const std::function<double(const Eigen::Vector3d&)>& reference,
                         double tolerance_m) {
  std::vector<std::vector<double>> errors(band_edges_m.size() + 1),
      signed_errors(band_edges_m.size() + 1);
  for (size_t i = 0; i < cells.free_centres.size(); ++i) {
    const double truth = reference(cells.free_centres[i]);
    if (!(truth <= max_distance_m)) continue;
    const double error = std::min(cells.free_distances_m[i], max_distance_m) - truth;
    const size_t band =
        std::upper_bound(band_edges_m.begin(), band_edges_m.end(), truth) - band_edges_m.begin();
    if (band >= band_edges_m.size()) continue;  // at or beyond the last edge
    for (size_t b : {band, band_edges_m.size()}) {
      errors[b].push_back(std::abs(error));
      signed_errors[b].push_back(error);
    }
  }
  EsdfAccuracy accuracy;
  accuracy.tolerance_m = tolerance_m;
  for (size_t b = 0; b < errors.size(); ++b) {
    EsdfBand band;
    band.lo_m = b == band_edges_m.size() || b == 0 ? 0.0 : band_edges_m[b - 1];
    band.hi_m = b == band_edges_m.size() ? band_edges_m.back() : band_edges_m[b];
    band.cells = errors[b].size();
    if (!errors[b].empty()) {
      std::vector<double> e = errors[b];
      std::sort(e.begin(), e.end());
      band.median_m = percentileOfSorted(e, 0.5);
      band.p99_m = percentileOfSorted(e, 0.99);
      band.max_m = e.back();
      band.over_tolerance =
          static_cast<size_t>(e.end() - std::upper_bound(e.begin(), e.end(), tolerance_m));
      double sum = 0;
      for (double s : signed_errors[b]) sum += s;
      band.mean_signed_m = sum / signed_errors[b].size();
    }
    accuracy.bands.push_back(band);
  }
  return accuracy;
}

std::string EsdfAccuracy::describe(const std::string& title) const {
  char head[160];
  std::snprintf(head, sizeof(head),
                "\n  band (m)      cells   median    p99     max    mean signed (m)  > %.3f m\n",
                tolerance_m);
  std::string out = title + head;
  char line[160];
  for (size_t b = 0; b < bands.size(); ++b) {
    const EsdfBand& x = bands[b];
    char band[32];
    if (b + 1 == bands.size())
      std::snprintf(band, sizeof(band), "all        ");
    else
      std::snprintf(band, sizeof(band), "%4.2f–%4.2f  ", x.lo_m, x.hi_m);
    std::snprintf(line, sizeof(line), "  %s %8zu  %.4f  %.4f  %.4f  %+.4f           %zu\n", band,
                  x.cells, x.median_m, x.p99_m, x.max_m, x.mean_signed_m, x.over_tolerance);
    out += line;
  }
  return out;
}

}  // namespace stereo_fusion
