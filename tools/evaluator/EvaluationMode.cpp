#include "evaluator/EvaluationMode.h"

#include <cctype>
#include <filesystem>

namespace stereo_fusion::eval {
namespace {

namespace fs = std::filesystem;

bool hasPlyExtension(const fs::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".ply";
}

}  // namespace

ModeError chooseEvaluationMode(const EvaluateArguments& args, EvaluationMode* mode,
                               std::string* error) {
  const fs::path reference(args.reference_path);
  std::error_code ec;
  const fs::file_status status = fs::status(reference, ec);
  if (!fs::exists(status)) {
    *error = args.reference_path + ": does not exist";
    return ModeError::kUnreadable;
  }
  *mode = EvaluationMode{};
  if (fs::is_directory(status)) {
    const fs::path gt_mesh = reference / "gt_mesh.ply";
    mode->ground_truth = !args.held_out_given && fs::exists(gt_mesh, ec);
    if (mode->ground_truth) mode->ground_truth_path = gt_mesh.string();
    mode->sequence_path = args.reference_path;
  } else if (!hasPlyExtension(reference)) {
    *error = args.reference_path + ": expected a ground-truth .ply or a sequence folder";
    return ModeError::kBadArguments;
  } else if (args.held_out_given) {
    *error = "--held-out needs a sequence folder, not a mesh";
    return ModeError::kBadArguments;
  } else {
    mode->ground_truth = true;
    mode->ground_truth_path = args.reference_path;
  }
  if (!mode->ground_truth && (!args.error_ply_path.empty() || !args.missing_ply_path.empty())) {
    *error = std::string(args.error_ply_path.empty() ? "--missing-ply" : "--error-ply") +
             " needs a ground truth (a .ply, or a sequence folder holding gt_mesh.ply "
             "without --held-out); " +
             args.reference_path + " is evaluated in held-out mode";
    return ModeError::kBadArguments;
  }
  if (mode->ground_truth && !args.held_out_depth_folder.empty()) {
    *error =
        "--held-out-depth needs held-out mode (a sequence folder without gt_mesh.ply, or "
        "--held-out); " +
        args.reference_path + " is evaluated against its ground truth";
    return ModeError::kBadArguments;
  }
  return ModeError::kNone;
}

}  // namespace stereo_fusion::eval
