#include "evaluator/EvaluationReport.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

namespace stereo_fusion::eval {
namespace {

using Json = nlohmann::ordered_json;  // keys keep insertion order, so reports diff cleanly

/// A number with 9 significant digits (1 nm at 1 km); null when not finite (JSON has no NaN or
/// infinity).
Json number(double value) {
  if (!std::isfinite(value)) return nullptr;
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.9g", value);
  return std::strtod(buffer, nullptr);
}

/// The document indented by two spaces, with a final newline. File names are copied as given: a
/// byte sequence that is not UTF-8 is replaced by U+FFFD rather than failing the report.
std::string dump(const Json& json) {
  return json.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

std::string format(const char* pattern, double value) {
  if (!std::isfinite(value)) return std::isnan(value) ? "n/a" : "inf";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), pattern, value);
  return buffer;
}

std::string millimetres(double metres) { return format("%.2f mm", metres * 1e3); }
std::string percent(double share) { return format("%.2f %%", share * 1e2); }

std::string row(const std::string& name, const std::string& value) {
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), "  %-34s %s\n", name.c_str(), value.c_str());
  return buffer;
}

/// The rows of a distance summary, in the order of the table.
std::string summaryRows(const DistanceSummary& summary) {
  return row("mean", millimetres(summary.mean_m)) + row("median", millimetres(summary.median_m)) +
         row("p90", millimetres(summary.p90_m)) + row("p99", millimetres(summary.p99_m)) +
         row("share > 10 cm", percent(summary.share_over_10cm));
}

Json summaryJson(const DistanceSummary& summary) {
  Json json;
  json["count"] = summary.count;
  json["mean"] = number(summary.mean_m);
  json["median"] = number(summary.median_m);
  json["p90"] = number(summary.p90_m);
  json["max"] = number(summary.max_m);
  json["p99"] = number(summary.p99_m);
  json["share_over_10cm"] = number(summary.share_over_10cm);
  return json;
}

}  // namespace

std::string formatTable(const GroundTruthReport& report) {
  const GroundTruthResult& r = report.result;
  std::string out = "Ground-truth evaluation\n";
  out += row("mesh", report.mesh_path);
  out += row("ground truth", report.ground_truth_path);
  if (!report.sequence_path.empty()) out += row("visibility from", report.sequence_path);
  out += row("tolerance", millimetres(report.options.tolerance_m));
  out += row("accuracy against", report.options.accuracy_triangles.empty()
                                     ? "all ground truth"
                                     : "the ground truth the frames saw (walls solid)");
  out += row("samples per mesh", std::to_string(report.options.samples) + " (seed " +
                                     std::to_string(report.options.seed) + ")");
  out += row("area reconstruction / truth", format("%.3f m²", r.reconstruction_area_m2) + " / " +
                                                format("%.3f m²", r.ground_truth_area_m2));
  out += "accuracy (reconstruction -> truth)\n";
  out += summaryRows(r.accuracy);
  out += "completion (truth -> reconstruction)\n";
  out += summaryRows(r.completion);
  out += "scores\n";
  out += row("precision", percent(r.precision));
  if (r.visibility_used) {
    out += row("completeness (visible truth)", percent(r.completeness));
    out += row("completeness (all truth)", percent(r.completeness_all));
    out += row("visible share of truth",
               percent(r.ground_truth_samples == 0
                           ? NAN
                           : static_cast<double>(r.ground_truth_samples_evaluated) /
                                 static_cast<double>(r.ground_truth_samples)));
    out += row("frames used / skipped", std::to_string(report.visibility.frames_used) + " / " +
                                            std::to_string(report.visibility.frames_skipped));
  } else {
    out += row("completeness", percent(r.completeness));
  }
  out += row("F-score", percent(r.f_score));
  if (!report.options.ghost_regions_m.empty())
    out += row("ghost surface (objects gone)",
               format("%.4f m²", r.ghost_area_m2) + " in " +
                   std::to_string(report.options.ghost_regions_m.size()) +
                   " region(s) of dynamic.txt");
  out += row("time", format("%.2f s", report.elapsed_s));
  return out;
}

std::string formatTable(const HeldOutReport& report) {
  const HeldOutResult& r = report.result;
  std::string out = "Held-out evaluation\n";
  out += row("mesh", report.mesh_path);
  out += row("sequence", report.sequence_path);
  out += row("held-out frames", report.held_out_spec + " (" +
                                    std::to_string(r.frames_evaluated.size()) + " evaluated, " +
                                    std::to_string(r.frames_skipped) + " skipped)");
  out += row("tolerance", millimetres(report.options.tolerance_m));
  out += row("measured depth range", format("%.2f", report.options.min_depth_m) + " .. " +
                                         format("%.2f m", report.options.max_depth_m));
  out += "depth residual |mesh - measured| (pixels with both)\n";
  out += row("median", millimetres(r.median_abs_residual_m));
  out += row("p90", millimetres(r.p90_abs_residual_m));
  out += row("p99", millimetres(r.p99_abs_residual_m));
  out += row("mean", millimetres(r.mean_abs_residual_m));
  out += row("share > 10 cm", percent(r.share_over_10cm));
  out += "scores\n";
  out += row("completeness (measured covered)", percent(r.completeness));
  out += row("floating (mesh in front)", percent(r.floating_share));
  out += row("pixels measured / mesh / both", std::to_string(r.total.measured_pixels) + " / " +
                                                  std::to_string(r.total.mesh_pixels) + " / " +
                                                  std::to_string(r.total.overlap_pixels));
  out += row("time", format("%.2f s", report.elapsed_s));
  return out;
}

std::string toJson(const GroundTruthReport& report) {
  const GroundTruthResult& r = report.result;
  Json json;
  json["mode"] = "ground_truth";
  json["mesh"] = report.mesh_path;
  json["ground_truth"] = report.ground_truth_path;
  json["sequence"] = report.sequence_path;
  json["tolerance_m"] = number(report.options.tolerance_m);
  json["samples"] = report.options.samples;
  json["seed"] = report.options.seed;
  json["accuracy_against"] = report.options.accuracy_triangles.empty() ? "all" : "seen";
  json["precision"] = number(r.precision);
  json["completeness"] = number(r.completeness);
  json["completeness_all"] = number(r.completeness_all);
  json["f_score"] = number(r.f_score);
  json["accuracy_m"] = summaryJson(r.accuracy);
  json["completion_m"] = summaryJson(r.completion);
  json["reconstruction_area_m2"] = number(r.reconstruction_area_m2);
  json["ground_truth_area_m2"] = number(r.ground_truth_area_m2);
  json["reconstruction_samples"] = r.reconstruction_samples;
  json["ground_truth_samples"] = r.ground_truth_samples;
  json["ground_truth_samples_evaluated"] = r.ground_truth_samples_evaluated;
  if (!report.options.ghost_regions_m.empty()) {
    json["ghost_area_m2"] = number(r.ghost_area_m2);
    json["ghost_regions"] = report.options.ghost_regions_m.size();
  }
  json["visibility"]["used"] = r.visibility_used;
  json["visibility"]["frames_used"] = report.visibility.frames_used;
  json["visibility"]["frames_skipped"] = report.visibility.frames_skipped;
  json["elapsed_s"] = number(report.elapsed_s);
  return dump(json);
}

std::string toJson(const HeldOutReport& report) {
  const HeldOutResult& r = report.result;
  const auto share = [](uint64_t numerator, uint64_t denominator) {
    return denominator == 0 ? NAN
                            : static_cast<double>(numerator) / static_cast<double>(denominator);
  };
  Json json;
  json["mode"] = "held_out";
  json["mesh"] = report.mesh_path;
  json["sequence"] = report.sequence_path;
  json["held_out"] = report.held_out_spec;
  json["tolerance_m"] = number(report.options.tolerance_m);
  json["min_depth_m"] = number(report.options.min_depth_m);
  json["max_depth_m"] = number(report.options.max_depth_m);
  json["median_abs_residual_m"] = number(r.median_abs_residual_m);
  json["p90_abs_residual_m"] = number(r.p90_abs_residual_m);
  json["mean_abs_residual_m"] = number(r.mean_abs_residual_m);
  json["p99_abs_residual_m"] = number(r.p99_abs_residual_m);
  json["share_over_10cm"] = number(r.share_over_10cm);
  json["floating_share"] = number(r.floating_share);
  json["completeness"] = number(r.completeness);
  json["pixels"]["measured"] = r.total.measured_pixels;
  json["pixels"]["mesh"] = r.total.mesh_pixels;
  json["pixels"]["both"] = r.total.overlap_pixels;
  json["pixels"]["agreeing"] = r.total.agreeing_pixels;
  json["pixels"]["floating"] = r.total.floating_pixels;
  json["pixels"]["over_10cm"] = r.total.over_10cm_pixels;
  json["frames_evaluated"] = r.frames_evaluated;
  json["frames_skipped"] = r.frames_skipped;
  json["per_frame"] = Json::array();
  for (size_t i = 0; i < r.per_frame.size(); ++i) {
    const HeldOutCounts& c = r.per_frame[i];
    Json frame;
    frame["frame"] = r.frames_evaluated[i];
    frame["mean_abs_residual_m"] = number(
        c.overlap_pixels == 0 ? NAN : c.abs_residual_sum_m / static_cast<double>(c.overlap_pixels));
    frame["floating_share"] = number(share(c.floating_pixels, c.overlap_pixels));
    frame["completeness"] = number(share(c.agreeing_pixels, c.measured_pixels));
    frame["measured_pixels"] = c.measured_pixels;
    frame["mesh_pixels"] = c.mesh_pixels;
    json["per_frame"].push_back(std::move(frame));
  }
  json["elapsed_s"] = number(report.elapsed_s);
  return dump(json);
}

}  // namespace stereo_fusion::eval
