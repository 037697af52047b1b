// stereo_fusion_soak: runs the soak (scripts/soak.sh) or plots soak CSVs.
#include <cstdio>
#include <string>
#include <vector>

#include "soak/SoakRun.h"

namespace {
const char* kUsage =
    "usage: stereo_fusion_soak --csv FILE [--frames N] [--sample-every K] [--width PX] [--height "
    "PX]\n"
    "                          [--speed M] [--set key=value ...]\n"
    "       stereo_fusion_soak --plot OUT.png LABEL=FILE.csv [LABEL=FILE.csv ...]\n"
    "Fuses N frames (default 10000) of an endless simulated corridor through the Mapper, the "
    "camera\n"
    "moving --speed metres (default 0.05) along it every frame, and writes the resident memory "
    "every K\n"
    "frames (default 100) to the CSV. --plot draws the RSS curves of several runs into a PNG.\n";

bool toSize(const std::string& text, size_t* out) {
  try {
    size_t used = 0;
    const long v = std::stol(text, &used);
    if (used != text.size() || v <= 0) return false;
    *out = static_cast<size_t>(v);
    return true;
  } catch (...) {
    return false;
  }
}
}  // namespace

int main(int argc, char** argv) {
  using namespace stereo_fusion;
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string error;
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::fputs(kUsage, args.empty() ? stderr : stdout);
    return args.empty() ? 2 : 0;
  }
  if (args[0] == "--plot") {
    if (args.size() < 3) {
      std::fputs(kUsage, stderr);
      return 2;
    }
    std::vector<std::pair<std::string, std::vector<soak::SoakSample>>> series;
    for (size_t i = 2; i < args.size(); ++i) {
      const size_t eq = args[i].rfind('=');  // labels may hold "=", paths rarely do
      if (eq == std::string::npos) {
        std::fprintf(stderr, "stereo_fusion_soak: expected LABEL=FILE.csv, got '%s'\n",
                     args[i].c_str());
        return 2;
      }
      series.emplace_back(args[i].substr(0, eq), std::vector<soak::SoakSample>{});
      if (!soak::readSoakCsv(args[i].substr(eq + 1), &series.back().second, &error)) {
        std::fprintf(stderr, "stereo_fusion_soak: %s\n", error.c_str());
        return 1;
      }
    }
    if (!soak::plotSoak(series, args[1], &error)) {
      std::fprintf(stderr, "stereo_fusion_soak: %s\n", error.c_str());
      return 1;
    }
    return 0;
  }
  soak::SoakOptions options;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (i + 1 >= args.size()) {
      std::fprintf(stderr, "stereo_fusion_soak: %s needs a value\n%s", a.c_str(), kUsage);
      return 2;
    }
    const std::string& v = args[++i];
    size_t n = 0;
    bool ok = true;
    if (a == "--csv") {
      options.csv_path = v;
    } else if (a == "--frames") {
      ok = toSize(v, &options.frames);
    } else if (a == "--sample-every") {
      ok = toSize(v, &options.sample_every);
    } else if (a == "--width" || a == "--height") {
      ok = toSize(v, &n) && n <= 4096;
      (a == "--width" ? options.width_px : options.height_px) = static_cast<int>(n);
    } else if (a == "--speed") {
      try {
        options.speed_m_per_frame = std::stod(v);
      } catch (...) {
        ok = false;
      }
    } else if (a == "--set") {
      const size_t eq = v.find('=');
      if (eq == std::string::npos ||
          !setMapperParameter(&options.config, v.substr(0, eq), v.substr(eq + 1), &error)) {
        std::fprintf(stderr, "stereo_fusion_soak: --set %s: %s\n", v.c_str(), error.c_str());
        return 2;
      }
    } else {
      std::fprintf(stderr, "stereo_fusion_soak: unknown option '%s'\n%s", a.c_str(), kUsage);
      return 2;
    }
    if (!ok) {
      std::fprintf(stderr, "stereo_fusion_soak: %s: '%s' is not valid\n", a.c_str(), v.c_str());
      return 2;
    }
  }
  if (options.csv_path.empty()) {
    std::fprintf(stderr, "stereo_fusion_soak: --csv is required\n%s", kUsage);
    return 2;
  }
  for (const std::string& e : validateMapperConfig(options.config)) {
    std::fprintf(stderr, "stereo_fusion_soak: %s\n", e.c_str());
    return 2;
  }
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
