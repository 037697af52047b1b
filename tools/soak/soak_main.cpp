// stereo_fusion_soak: runs the soak (scripts/soak.sh) or plots soak CSVs.
#include <cstdio>
#include <string>
#include <vector>

#include "cli/CommandLine.h"
#include "cli/MapperConfigArguments.h"
#include "cli/NumberChecks.h"
#include "soak/SoakRun.h"

namespace {

using namespace stereo_fusion;

/// The command line: a run (--csv) or a plot (--plot) of earlier runs.
struct SoakArguments {
  soak::SoakOptions run;
  cli::MapperConfigArguments config;
  std::string plot_path;            ///< --plot OUT.png; empty: a run
  std::vector<std::string> series;  ///< with --plot: LABEL=FILE.csv
};

void addSoakArguments(CLI::App* app, SoakArguments* a) {
  app->description(
      "Fuses N frames (default 10000) of an endless simulated corridor through the Mapper, the\n"
      "camera moving --speed metres (default 0.05) along it every frame, and writes the resident\n"
      "memory every K frames (default 100) to the CSV. --plot draws the RSS curves of several\n"
      "runs into a PNG:\n"
      "  stereo_fusion_soak --csv FILE [--frames N] [--sample-every K] [--width PX] [--height PX]\n"
      "                     [--speed M] [--config FILE] [--set key=value ...]\n"
      "  stereo_fusion_soak --plot OUT.png LABEL=FILE.csv [LABEL=FILE.csv ...]");
  app->footer("Exit codes: 0 done, 1 the run or the plot failed, 2 bad arguments.");
  CLI::Option* csv = app->add_option("--csv", a->run.csv_path, "the run's CSV, one row per sample")
                         ->type_name("FILE");
  app->add_option("--frames", a->run.frames, "frames to fuse (default 10000)")
      ->check(cli::positiveNumber());
  app->add_option("--sample-every", a->run.sample_every, "frames between samples (default 100)")
      ->check(cli::positiveNumber());
  app->add_option("--width", a->run.width_px, "image width of the simulated camera (default 160)")
      ->check(CLI::Range(1, 4096));
  app->add_option("--height", a->run.height_px,
                  "image height of the simulated camera (default 120)")
      ->check(CLI::Range(1, 4096));
  app->add_option("--speed", a->run.speed_m_per_frame,
                  "metres the camera moves along the corridor every frame (default 0.05)")
      ->check(cli::finiteNumber());
  cli::addMapperConfigArguments(app, &a->config);
  CLI::Option* plot = app->add_option("--plot", a->plot_path,
                                      "draw the RSS curves of the runs given as LABEL=FILE.csv")
                          ->type_name("OUT.png")
                          ->excludes(csv);
  CLI::Option* series =
      app->add_option("series", a->series, "with --plot: a run's CSV and its label in the plot")
          ->type_name("LABEL=FILE.csv")
          ->check(CLI::Validator(
              [](std::string& value) {  // labels may hold "=", paths rarely do: the last splits
                return value.rfind('=') == std::string::npos
                           ? "expected LABEL=FILE.csv, got '" + value + "'"
                           : std::string();
              },
              ""))
          ->needs(plot);
  plot->needs(series);
  app->callback([a] {
    if (!a->plot_path.empty()) return;
    if (a->run.csv_path.empty())
      throw CLI::ValidationError("--csv FILE or --plot OUT.png is required");
    std::string error;
    if (!cli::applyMapperConfigArguments(a->config, &a->run.config, &error))
      throw CLI::ValidationError(error);
  });
}

int plot(const SoakArguments& a) {
  std::string error;
  std::vector<std::pair<std::string, std::vector<soak::SoakSample>>> series;
  for (const std::string& labelled : a.series) {
    const size_t eq = labelled.rfind('=');
    series.emplace_back(labelled.substr(0, eq), std::vector<soak::SoakSample>{});
    if (!soak::readSoakCsv(labelled.substr(eq + 1), &series.back().second, &error)) {
      std::fprintf(stderr, "stereo_fusion_soak: %s\n", error.c_str());
      return 1;
    }
  }
  if (!soak::plotSoak(series, a.plot_path, &error)) {
    std::fprintf(stderr, "stereo_fusion_soak: %s\n", error.c_str());
    return 1;
  }
  return 0;
}

int run(const soak::SoakOptions& options) {
  std::string error;
  std::vector<soak::SoakSample> samples;
  if (!soak::runSoak(options, &samples, &error)) {
    std::fprintf(stderr, "stereo_fusion_soak: %s\n", error.c_str());
    return 1;
  }
  const soak::SoakSample& first = samples.front();
  const soak::SoakSample& mid = samples[samples.size() / 2];
  const soak::SoakSample& last = samples.back();
  std::printf(
      "RSS MiB at frame %zu / %zu / %zu: %.1f / %.1f / %.1f; blocks %zu / %zu / %zu; evicted "
      "%llu\n",
      first.frame, mid.frame, last.frame, first.rss_mb, mid.rss_mb, last.rss_mb, first.blocks,
      mid.blocks, last.blocks, last.evicted);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  SoakArguments arguments;
  CLI::App app("", "stereo_fusion_soak");
  addSoakArguments(&app, &arguments);
  if (const auto exit_code = stereo_fusion::cli::parseOrExitCode(app, argc, argv))
    return *exit_code;
  return arguments.plot_path.empty() ? run(arguments.run) : plot(arguments);
}
