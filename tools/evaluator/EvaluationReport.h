#pragma once
// Human-readable tables and JSON documents of the evaluation results.

#include <string>

#include "evaluator/HeldOutEvaluator.h"
#include "evaluator/MeshEvaluator.h"
#include "evaluator/SampleVisibility.h"

namespace stereo_fusion::eval {

/// A ground-truth evaluation with what it was run on.
struct GroundTruthReport {
  std::string mesh_path;
  std::string ground_truth_path;
  std::string sequence_path;  ///< empty without visibility
  GroundTruthOptions options;
  GroundTruthResult result;
  VisibilityResult visibility;  ///< empty without a sequence
  double elapsed_s = 0.0;
};

/// A held-out evaluation with what it was run on.
struct HeldOutReport {
  std::string mesh_path;
  std::string sequence_path;
  std::string held_out_spec;
  HeldOutOptions options;
  HeldOutResult result;
  double elapsed_s = 0.0;
};

/// Aligned text table (metres shown in mm or m as fits, shares in %).
std::string formatTable(const GroundTruthReport& report);
std::string formatTable(const HeldOutReport& report);

/// JSON document: every distance in metres, every share a fraction, null for undefined values.
std::string toJson(const GroundTruthReport& report);
std::string toJson(const HeldOutReport& report);

}  // namespace stereo_fusion::eval
