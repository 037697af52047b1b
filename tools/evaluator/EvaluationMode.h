#pragma once
// Which evaluation the command line asks for: ground truth or held-out frames.

#include <string>

#include "evaluator/EvaluateArguments.h"

namespace stereo_fusion::eval {

/// What to run, and on what.
struct EvaluationMode {
  bool ground_truth = false;      ///< false: held-out frames
  std::string ground_truth_path;  ///< ground-truth mode: the .ply
  std::string sequence_path;      ///< frames: visibility (may be empty) or the held-out frames
};

/// Why no mode could be chosen, to pick the exit code.
enum class ModeError { kNone, kUnreadable, kBadArguments };

/// Chooses the mode from the second argument (see --help): a .ply → ground truth; a
/// folder with gt_mesh.ply → ground truth with visibility, unless --held-out is given; any other
/// folder → held-out. Refuses options the chosen mode cannot honour (--held-out with a .ply,
/// --error-ply in held-out mode) before any work is done.
ModeError chooseEvaluationMode(const EvaluateArguments& args, EvaluationMode* mode,
                               std::string* error);

}  // namespace stereo_fusion::eval
