#pragma once
// One ESDF against an earlier one of the same frames, cell by cell: does a change of the
// planning layer make any cell read worse against the truth?

#include <functional>
#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "evaluator/EsdfAccuracy.h"

namespace stereo_fusion::eval {

struct CellDelta {
  double cell_m = 0.0;
  size_t now_cells = 0;         ///< free cells of the newer ESDF
  size_t both_free = 0;         ///< ... that the earlier one also calls free (same centre)
  size_t worse = 0;             ///< of those: |error| grew by more than half a cell
  size_t better = 0;            ///< of those: |error| shrank by more than half a cell
  double worst_growth_m = 0.0;  ///< the largest growth of |error|
  size_t lost_free = 0;         ///< free before, unknown or occupied now
  std::string describe(const std::string& before_path) const;
};

/// Free cells of `now` and `before` at the same centres (within a tenth of `cell_m`), each
/// error |min(d, max) − min(truth, max)| with truth = `signed_truth(centre)`.
CellDelta compareWithBefore(const EsdfCells& now, const EsdfCells& before, double max_distance_m,
                            double cell_m,
                            const std::function<double(const Eigen::Vector3d&)>& signed_truth);

nlohmann::ordered_json toJson(const CellDelta& delta, const std::string& before_path);

}  // namespace stereo_fusion::eval
