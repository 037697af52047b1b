// stereo_fusion_evaluate: scores a reconstructed mesh against a ground-truth mesh, or against
// held-out frames of a sequence without ground truth; --help for the interface.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "cli/CommandLine.h"
#include "evaluator/ErrorColouredMesh.h"
#include "evaluator/EvaluateArguments.h"
#include "evaluator/EvaluationMode.h"
#include "evaluator/EvaluationReport.h"
#include "evaluator/HeldOutSelection.h"
#include "evaluator/SeenTriangles.h"
#include "evaluator/SurfaceSampler.h"
#include "readers/DatasetReader.h"
#include "readers/PlyReader.h"

namespace fs = std::filesystem;
using namespace stereo_fusion;
using namespace stereo_fusion::eval;

namespace {

constexpr int kExitOk = 0;
constexpr int kExitUnreadable = 1;
constexpr int kExitBadArguments = cli::kExitBadArguments;
/// A triangle counts as seen when its centroid lies within this of the truth's own depth image.
constexpr double kSeenToleranceM = 0.02;

/// Thrown on a failure that ends the program with `exit_code`.
struct Failure {
  int exit_code;
  std::string message;
};

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TriangleMesh readMeshOrFail(const std::string& path, const char* role) {
  TriangleMesh mesh;
  std::string error;
  if (!readPly(path, &mesh, &error)) throw Failure{kExitUnreadable, error};
  std::fprintf(stderr, "[evaluate] %s: %zu vertices, %zu triangles\n", role, mesh.positions.size(),
               mesh.triangles.size());
  if (mesh.triangles.empty()) std::fprintf(stderr, "[evaluate] warning: %s has no faces\n", role);
  return mesh;
}

DatasetReader openSequenceOrFail(const std::string& folder) {
  std::string error;
  std::optional<DatasetReader> reader = DatasetReader::open(folder, &error);
  if (!reader) throw Failure{kExitUnreadable, error};
  std::fprintf(stderr, "[evaluate] sequence %s: %zu frames\n", folder.c_str(), reader->size());
  return std::move(*reader);
}

void writeJsonOrFail(const std::string& path, const std::string& json) {
  if (path.empty()) return;
  std::ofstream out(path);
  out << json;
  if (!out) throw Failure{kExitUnreadable, path + ": cannot write the JSON report"};
  std::fprintf(stderr, "[evaluate] wrote %s\n", path.c_str());
}

void writeErrorPlyOrFail(const EvaluateArguments& args, const TriangleMesh& reconstruction,
                         const TriangleMesh& ground_truth) {
  if (args.error_ply_path.empty()) return;
  std::string error;
  if (!writeErrorColouredPly(args.error_ply_path, reconstruction, ground_truth, args.tolerance_m,
                             args.threads, &error)) {
    throw Failure{kExitUnreadable, error};
  }
  std::fprintf(stderr, "[evaluate] wrote error-coloured mesh to %s\n", args.error_ply_path.c_str());
}

/// The regions of `sequence`/dynamic.txt ("ghost_region x0 y0 z0 x1 y1 z1" lines, world metres,
/// written by the simulator's --dynamic): where objects stood that later left. No file: none.
bool readGhostRegions(const std::string& sequence, std::vector<Eigen::AlignedBox3d>* regions,
                      std::string* error) {
  const std::string path = sequence + "/dynamic.txt";
  std::ifstream in(path);
  if (!in) return true;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream fields(line);
    std::string kind;
    if (!(fields >> kind) || kind[0] == '#') continue;
    Eigen::Vector3d lo, hi;
    if (kind != "ghost_region" ||
        !(fields >> lo.x() >> lo.y() >> lo.z() >> hi.x() >> hi.y() >> hi.z()) ||
        !(lo.array() <= hi.array()).all()) {
      *error = path + ":" + std::to_string(number) +
               ": expected 'ghost_region x0 y0 z0 x1 y1 z1' with x0 <= x1 ...";
      return false;
    }
    regions->emplace_back(lo, hi);
  }
  return true;
}

void runGroundTruth(const EvaluateArguments& args, const std::string& gt_path,
                    const std::string& sequence) {
  const auto start = std::chrono::steady_clock::now();
  GroundTruthReport report;
  report.mesh_path = args.mesh_path;
  report.ground_truth_path = gt_path;
  report.sequence_path = sequence;
  report.options.tolerance_m = args.tolerance_m;
  report.options.samples = args.samples;
  report.options.seed = args.seed;
  report.options.num_threads = args.threads;

  const TriangleMesh reconstruction = readMeshOrFail(args.mesh_path, "mesh");
  const TriangleMesh ground_truth = readMeshOrFail(gt_path, "ground truth");
  const SurfaceSamples gt_samples = sampleSurface(ground_truth, args.samples, args.seed);
  if (gt_samples.points_m.empty())
    throw Failure{kExitUnreadable, gt_path + ": has no surface area"};
  if (!sequence.empty()) {
    std::string error;
    if (!readGhostRegions(sequence, &report.options.ghost_regions_m, &error))
      throw Failure{kExitUnreadable, error};
    const DatasetReader frames = openSequenceOrFail(sequence);
    report.visibility =
        computeVisibility(gt_samples.points_m, frames, args.tolerance_m, args.threads);
    for (const std::string& reason : report.visibility.skipped) {
      std::fprintf(stderr, "[evaluate] skipped frame: %s\n", reason.c_str());
    }
    if (report.visibility.visible_count == 0) {
      std::fprintf(stderr, "[evaluate] warning: no ground-truth sample is visible in %s\n",
                   sequence.c_str());
    }
    if (args.accuracy_against_seen) {
      report.options.accuracy_triangles =
          seenTriangles(ground_truth, frames, kSeenToleranceM, args.threads);
      size_t seen = 0;
      for (uint8_t s : report.options.accuracy_triangles) seen += s;
      std::fprintf(stderr, "[evaluate] accuracy against the %zu of %zu triangles the frames saw\n",
                   seen, ground_truth.triangles.size());
    }
  } else if (args.accuracy_against_seen) {
    throw Failure{kExitBadArguments, "--accuracy-against seen needs the sequence folder"};
  }
  report.result = evaluateAgainstGroundTruthSamples(reconstruction, ground_truth,
                                                    gt_samples.points_m, gt_samples.area_m2,
                                                    report.visibility.visible, report.options);
  report.elapsed_s = secondsSince(start);
  std::cout << formatTable(report);
  writeJsonOrFail(args.json_path, toJson(report));
  writeErrorPlyOrFail(args, reconstruction, ground_truth);
  if (!args.missing_ply_path.empty()) {
    std::string error;
    if (!writeMissingPly(args.missing_ply_path, gt_samples.points_m, report.visibility.visible,
                         report.result.gt_sample_distances_m, args.tolerance_m, &error)) {
      throw Failure{kExitUnreadable, error};
    }
    std::fprintf(stderr, "[evaluate] wrote the ground-truth samples coloured by distance to %s\n",
                 args.missing_ply_path.c_str());
  }
}

void runHeldOut(const EvaluateArguments& args) {
  const auto start = std::chrono::steady_clock::now();
  HeldOutReport report;
  report.mesh_path = args.mesh_path;
  report.sequence_path = args.reference_path;
  report.held_out_spec = args.held_out_spec;
  report.options.tolerance_m = args.tolerance_m;
  report.options.min_depth_m = args.min_depth_m;
  report.options.max_depth_m = args.max_depth_m;
  report.options.num_threads = args.threads;
  report.options.rendered_depth_folder = args.held_out_depth_folder;

  const TriangleMesh mesh = readMeshOrFail(args.mesh_path, "mesh");
  const DatasetReader frames = openSequenceOrFail(args.reference_path);
  std::vector<size_t> held_out;
  std::string error;
  if (!parseHeldOutFrames(args.held_out_spec, frames.size(), &held_out, &error)) {
    throw Failure{kExitBadArguments, error};
  }
  report.result = evaluateHeldOut(mesh, frames, held_out, report.options);
  for (const std::string& reason : report.result.skipped) {
    std::fprintf(stderr, "[evaluate] skipped frame: %s\n", reason.c_str());
  }
  if (report.result.frames_evaluated.empty()) {
    throw Failure{kExitUnreadable, "none of the held-out frames could be loaded"};
  }
  report.elapsed_s = secondsSince(start);
  std::cout << formatTable(report);
  writeJsonOrFail(args.json_path, toJson(report));
}

/// Fails before minutes of work, not after, when an output cannot be written.
void checkOutputFolderOrFail(const std::string& path) {
  if (path.empty()) return;
  const fs::path parent = fs::absolute(path).parent_path();
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) {
    throw Failure{kExitUnreadable, path + ": folder " + parent.string() + " does not exist"};
  }
}

/// Chooses the mode from the second argument (see the usage text) and runs it.
void run(const EvaluateArguments& args) {
  EvaluationMode mode;
  std::string error;
  switch (chooseEvaluationMode(args, &mode, &error)) {
    case ModeError::kNone: break;
    case ModeError::kUnreadable: throw Failure{kExitUnreadable, error};
    case ModeError::kBadArguments: throw Failure{kExitBadArguments, error};
  }
  checkOutputFolderOrFail(args.json_path);
  checkOutputFolderOrFail(args.error_ply_path);
  checkOutputFolderOrFail(args.missing_ply_path);
  checkOutputFolderOrFail(args.held_out_depth_folder.empty() ? ""
                                                             : args.held_out_depth_folder + "/");
  if (mode.ground_truth) {
    runGroundTruth(args, mode.ground_truth_path, mode.sequence_path);
  } else {
    runHeldOut(args);
  }
}

}  // namespace

int main(int argc, char** argv) {
  EvaluateArguments args;
  CLI::App app("", "stereo_fusion_evaluate");
  addEvaluateArguments(&app, &args);
  if (const auto exit_code = cli::parseOrExitCode(app, argc, argv)) return *exit_code;
  try {
    run(args);
  } catch (const Failure& failure) {
    std::fprintf(stderr, "error: %s\n", failure.message.c_str());
    if (failure.exit_code == kExitBadArguments)
      std::fprintf(stderr, "Run with --help for more information.\n");
    return failure.exit_code;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "error: out of memory (try fewer --samples)\n");
    return kExitUnreadable;
  }
  return kExitOk;
}
