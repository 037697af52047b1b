#include "evaluator/EvaluateArguments.h"

#include "cli/CommandLine.h"
#include "cli/NumberChecks.h"

namespace stereo_fusion::eval {

void addEvaluateArguments(CLI::App* app, EvaluateArguments* parsed) {
  app->description(
      "Scores a reconstructed mesh.\n"
      "  <gt_mesh.ply>             ground-truth mode: accuracy, completeness, precision, F-score\n"
      "  <seq-folder>/gt_mesh.ply  ground-truth mode, completeness over the ground truth the\n"
      "                            sequence's frames saw\n"
      "  <seq-folder> (no GT)      held-out mode: the mesh rendered into frames that were not\n"
      "                            fused, compared with their measured depth");
  app->footer("Exit codes: 0 ok, 1 unreadable input or output, 2 bad arguments.");
  app->add_option("mesh", parsed->mesh_path, "the reconstructed mesh (.ply)")->required();
  app->add_option("reference", parsed->reference_path,
                  "<gt_mesh.ply | seq-folder>: the ground truth, or the sequence (see above)")
      ->required();
  app->add_option("--tolerance-m", parsed->tolerance_m,
                  "agreement distance in metres (default 0.04 = 2 voxels)")
      ->check(cli::positiveNumber());
  app->add_option("--json", parsed->json_path, "also write the results as JSON (metres, fractions)")
      ->type_name("FILE");
  app->add_option("--error-ply", parsed->error_ply_path,
                  "ground-truth mode: also write the mesh (same vertices and faces) as binary\n"
                  "PLY coloured by each vertex's distance to the ground truth: blue 0, green\n"
                  "tolerance/2, yellow tolerance, red 2 x tolerance and beyond, linear in between")
      ->type_name("FILE");
  app->add_option("--missing-ply", parsed->missing_ply_path,
                  "ground-truth mode: also write the evaluated ground-truth samples as a binary\n"
                  "PLY point cloud, coloured the same way by their distance to the mesh: red\n"
                  "where the mesh is missing")
      ->type_name("FILE");
  app->add_option_function<std::string>(
         "--held-out",
         [parsed](const std::string& spec) {
           parsed->held_out_spec = spec;
           parsed->held_out_given = true;
         },
         "held-out frames: odd | even | i,j,k (default odd); forces held-out mode on a folder\n"
         "that has gt_mesh.ply")
      ->type_name("SPEC");
  app->add_option("--held-out-depth", parsed->held_out_depth_folder,
                  "held-out mode: also write the mesh's depth as each held-out frame sees it,\n"
                  "DIR/<frame index>.tiff (32-bit float metres, 0 = no mesh), to compare two\n"
                  "meshes pixel by pixel")
      ->type_name("DIR");
  // The cap keeps the sample arrays (24 bytes each, two meshes) within a few GB.
  app->add_option("--samples", parsed->samples,
                  "surface samples per mesh in ground-truth mode (default 1000000)")
      ->check(CLI::Range(size_t{1}, size_t{100000000}));
  app->add_option("--seed", parsed->seed, "sampling seed (default 1)")
      ->check(cli::nonNegativeNumber());
  app->add_option("--min-depth-m", parsed->min_depth_m,
                  "held-out: ignore measurements nearer than X metres (default 0.1)")
      ->check(cli::nonNegativeNumber());
  app->add_option("--max-depth-m", parsed->max_depth_m,
                  "held-out: ignore measurements farther than X metres (default 8)")
      ->check(cli::positiveNumber());
  app->add_option_function<std::string>(
         "--accuracy-against",
         [parsed](const std::string& value) { parsed->accuracy_against_seen = value == "seen"; },
         "ground-truth mode with a sequence: measure the mesh's accuracy against every\n"
         "ground-truth triangle (all, the default) or only those the frames' cameras saw;\n"
         "with seen, walls count as solid: a surface behind a wall is an error measured to\n"
         "the wall, not a near miss of its hidden back or of what stands behind it")
      ->check(CLI::IsMember({"all", "seen"}));
  app->add_option("--threads", parsed->threads, "worker threads, 0 = all cores (default 0)")
      ->check(CLI::Range(0, 256));
  app->callback([parsed] {
    if (parsed->min_depth_m >= parsed->max_depth_m)
      throw CLI::ValidationError("--min-depth-m must be smaller than --max-depth-m");
  });
}

bool parseEvaluateArguments(const std::vector<std::string>& args, EvaluateArguments* parsed,
                            std::string* error) {
  CLI::App app;
  addEvaluateArguments(&app, parsed);
  return cli::parseArguments(app, args, error);
}

}  // namespace stereo_fusion::eval
