#include "evaluator/EvaluateArguments.h"

#include <charconv>
#include <cmath>

namespace stereo_fusion::eval {
namespace {

template <typename T>
bool parseNumber(const std::string& text, T* value) {
  const char* end = text.data() + text.size();
  const auto [parsed_end, ec] = std::from_chars(text.data(), end, *value);
  return !text.empty() && ec == std::errc() && parsed_end == end;
}

bool positiveFinite(double value) { return std::isfinite(value) && value > 0.0; }

}  // namespace

std::string evaluateUsage() {
  return "usage: stereo_fusion_evaluate <mesh.ply> <gt_mesh.ply | seq-folder> [options]\n"
         "\n"
         "Scores a reconstructed mesh.\n"
         "  <gt_mesh.ply>             ground-truth mode: accuracy, completeness, precision, "
         "F-score\n"
         "  <seq-folder>/gt_mesh.ply  ground-truth mode, completeness over the ground truth the\n"
         "                            sequence's frames saw\n"
         "  <seq-folder> (no GT)      held-out mode: the mesh rendered into frames that were not\n"
         "                            fused, compared with their measured depth\n"
         "\n"
         "options:\n"
         "  --tolerance-m X   agreement distance in metres (default 0.04 = 2 voxels)\n"
         "  --json FILE       also write the results as JSON (metres, fractions)\n"
         "  --error-ply FILE  ground-truth mode: also write the mesh (same vertices and faces)\n"
         "                    as binary PLY coloured by each vertex's distance to the ground\n"
         "                    truth: blue 0, green tolerance/2, yellow tolerance, red 2 x\n"
         "                    tolerance and beyond, linear in between\n"
         "  --missing-ply FILE  ground-truth mode: also write the evaluated ground-truth\n"
         "                    samples as a binary PLY point cloud, coloured the same way by\n"
         "                    their distance to the mesh: red where the mesh is missing\n"
         "  --held-out SPEC   held-out frames: odd | even | i,j,k (default odd); forces\n"
         "                    held-out mode on a folder that has gt_mesh.ply\n"
         "  --held-out-depth DIR  held-out mode: also write the mesh's depth as each held-out\n"
         "                    frame sees it, DIR/<frame index>.tiff (32-bit float metres, 0 =\n"
         "                    no mesh), to compare two meshes pixel by pixel\n"
         "  --samples N       surface samples per mesh in ground-truth mode (default 1000000)\n"
         "  --seed K          sampling seed (default 1)\n"
         "  --min-depth-m X   held-out: ignore measurements nearer than X (default 0.1)\n"
         "  --max-depth-m X   held-out: ignore measurements farther than X (default 8)\n"
         "  --accuracy-against all|seen  ground-truth mode with a sequence: measure the mesh's\n"
         "                    accuracy against every ground-truth triangle (default) or only\n"
         "                    those the frames' cameras saw; with seen, walls count as solid:\n"
         "                    a surface behind a wall is an error measured to the wall, not a\n"
         "                    near miss of its hidden back or of what stands behind it\n"
         "  --threads N       worker threads, 0 = all cores (default 0)\n"
         "  -h, --help        this text\n"
         "\n"
         "exit codes: 0 ok, 1 unreadable input or output, 2 bad arguments\n";
}

bool parseEvaluateArguments(const std::vector<std::string>& args, EvaluateArguments* parsed,
                            std::string* error) {
  std::vector<std::string> positional;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "-h" || arg == "--help") {
      parsed->help = true;
      return true;
    }
    if (arg.rfind("--", 0) != 0 || arg == "--") {
      positional.push_back(arg);
      continue;
    }
    // Every option takes one value.
    if (i + 1 >= args.size()) {
      *error = arg + " needs a value";
      return false;
    }
    const std::string& value = args[++i];
    const std::string bad = "bad value \"" + value + "\" for " + arg;
    if (arg == "--tolerance-m") {
      if (!parseNumber(value, &parsed->tolerance_m) || !positiveFinite(parsed->tolerance_m)) {
        *error = bad + " (a distance in metres > 0)";
        return false;
      }
    } else if (arg == "--json") {
      parsed->json_path = value;
    } else if (arg == "--error-ply") {
      parsed->error_ply_path = value;
    } else if (arg == "--missing-ply") {
      parsed->missing_ply_path = value;
    } else if (arg == "--held-out-depth") {
      parsed->held_out_depth_folder = value;
    } else if (arg == "--held-out") {
      parsed->held_out_spec = value;
      parsed->held_out_given = true;
    } else if (arg == "--samples") {
      // The cap keeps the sample arrays (24 bytes each, two meshes) within a few GB.
      if (!parseNumber(value, &parsed->samples) || parsed->samples == 0 ||
          parsed->samples > 100000000) {
        *error = bad + " (an integer in [1, 100000000])";
        return false;
      }
    } else if (arg == "--seed") {
      if (!parseNumber(value, &parsed->seed)) {
        *error = bad + " (a non-negative integer)";
        return false;
      }
    } else if (arg == "--min-depth-m") {
      if (!parseNumber(value, &parsed->min_depth_m) || !std::isfinite(parsed->min_depth_m) ||
          parsed->min_depth_m < 0.0) {
        *error = bad + " (a depth in metres >= 0)";
        return false;
      }
    } else if (arg == "--max-depth-m") {
      if (!parseNumber(value, &parsed->max_depth_m) || !positiveFinite(parsed->max_depth_m)) {
        *error = bad + " (a depth in metres > 0)";
        return false;
      }
    } else if (arg == "--accuracy-against") {
      if (value != "all" && value != "seen") {
        *error = bad + " (all or seen)";
        return false;
      }
      parsed->accuracy_against_seen = value == "seen";
    } else if (arg == "--threads") {
      if (!parseNumber(value, &parsed->threads) || parsed->threads < 0 || parsed->threads > 256) {
        *error = bad + " (an integer in [0, 256])";
        return false;
      }
    } else {
      *error = "unknown option " + arg;
      return false;
    }
  }
  if (positional.size() != 2) {
    *error = "expected 2 arguments (mesh and ground truth or sequence folder), got " +
             std::to_string(positional.size());
    return false;
  }
  if (parsed->min_depth_m >= parsed->max_depth_m) {
    *error = "--min-depth-m must be smaller than --max-depth-m";
    return false;
  }
  parsed->mesh_path = positional[0];
  parsed->reference_path = positional[1];
  return true;
}

}  // namespace stereo_fusion::eval
