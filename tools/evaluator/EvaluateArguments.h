#pragma once
// Command line of stereo_fusion_evaluate.

#include <cstdint>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace stereo_fusion::eval {

/// Everything the command line can set, with the defaults documented in the usage text.
struct EvaluateArguments {
  std::string mesh_path;       ///< reconstruction (.ply)
  std::string reference_path;  ///< ground-truth .ply or sequence folder
  double tolerance_m = 0.04;
  std::string json_path;       ///< empty: no JSON file
  std::string error_ply_path;  ///< empty: no error-coloured mesh (ground-truth mode only)
  std::string
      missing_ply_path;  ///< empty: no coloured ground-truth samples (ground-truth mode only)
  std::string held_out_depth_folder;  ///< empty: rendered depths not written (held-out mode only)
  std::string held_out_spec = "odd";
  bool held_out_given = false;  ///< --held-out forces held-out mode on a folder with gt_mesh.ply
  size_t samples = 1000000;
  uint64_t seed = 1;
  double min_depth_m = 0.1;
  double max_depth_m = 8.0;
  int threads = 0;
  /// Ground-truth mode: score accuracy against only the triangles the frames saw (walls solid).
  bool accuracy_against_seen = false;
};

/// Adds stereo_fusion_evaluate's arguments and their usage text to `app`, parsed into `parsed`
/// (which must outlive the parse). Malformed or out-of-range values, unknown options and a
/// wrong number of positional arguments end the parse with a CLI11 error (exit code 2).
void addEvaluateArguments(CLI::App* app, EvaluateArguments* parsed);

/// Parses argv[1..]. Returns false with a one-line reason for unknown options, missing or
/// malformed values and a wrong number of positional arguments.
bool parseEvaluateArguments(const std::vector<std::string>& args, EvaluateArguments* parsed,
                            std::string* error);

}  // namespace stereo_fusion::eval
