#include "evaluator/EvaluationReport.h"

#include <cmath>
#include <cstdio>

#include "evaluator/JsonWriter.h"

namespace stereo_fusion::eval {
namespace {

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

JsonObject summaryJson(const DistanceSummary& summary) {
  JsonObject json;
  json.integer("count", summary.count)
      .number("mean", summary.mean_m)
      .number("median", summary.median_m)
      .number("p90", summary.p90_m)
      .number("max", summary.max_m);
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
  out += row("samples per mesh", std::to_string(report.options.samples) + " (seed " +
                                     std::to_string(report.options.seed) + ")");
  out += row("area reconstruction / truth",
             format("%.3f m²", r.reconstruction_area_m2) + " / " +
                 format("%.3f m²", r.ground_truth_area_m2));
  out += "accuracy (reconstruction -> truth)\n";
  out += row("mean", millimetres(r.accuracy.mean_m));
  out += row("median", millimetres(r.accuracy.median_m));
  out += row("p90", millimetres(r.accuracy.p90_m));
  out += "completion (truth -> reconstruction)\n";
  out += row("mean", millimetres(r.completion.mean_m));
  out += row("median", millimetres(r.completion.median_m));
  out += row("p90", millimetres(r.completion.p90_m));
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
  out += row("mean", millimetres(r.mean_abs_residual_m));
  out += "scores\n";
  out += row("completeness (measured covered)", percent(r.completeness));
  out += row("floating (mesh in front)", percent(r.floating_share));
  out += row("pixels measured / mesh / both",
             std::to_string(r.total.measured_pixels) + " / " + std::to_string(r.total.mesh_pixels) +
                 " / " + std::to_string(r.total.overlap_pixels));
  out += row("time", format("%.2f s", report.elapsed_s));
  return out;
}

std::string toJson(const GroundTruthReport& report) {
  const GroundTruthResult& r = report.result;
  JsonObject json;
  json.text("mode", "ground_truth")
      .text("mesh", report.mesh_path)
      .text("ground_truth", report.ground_truth_path)
      .text("sequence", report.sequence_path)
      .number("tolerance_m", report.options.tolerance_m)
      .integer("samples", report.options.samples)
      .integer("seed", report.options.seed)
      .number("precision", r.precision)
      .number("completeness", r.completeness)
      .number("completeness_all", r.completeness_all)
      .number("f_score", r.f_score)
      .object("accuracy_m", summaryJson(r.accuracy))
      .object("completion_m", summaryJson(r.completion))
      .number("reconstruction_area_m2", r.reconstruction_area_m2)
      .number("ground_truth_area_m2", r.ground_truth_area_m2)
      .integer("reconstruction_samples", r.reconstruction_samples)
      .integer("ground_truth_samples", r.ground_truth_samples)
      .integer("ground_truth_samples_evaluated", r.ground_truth_samples_evaluated);
  JsonObject visibility;
  visibility.boolean("used", r.visibility_used)
      .integer("frames_used", report.visibility.frames_used)
      .integer("frames_skipped", report.visibility.frames_skipped);
  json.object("visibility", visibility).number("elapsed_s", report.elapsed_s);
  return json.str() + "\n";
}

std::string toJson(const HeldOutReport& report) {
  const HeldOutResult& r = report.result;
  const auto share = [](uint64_t numerator, uint64_t denominator) {
    return denominator == 0 ? NAN : static_cast<double>(numerator) / static_cast<double>(denominator);
  };
  JsonObject json;
  json.text("mode", "held_out")
      .text("mesh", report.mesh_path)
      .text("sequence", report.sequence_path)
      .text("held_out", report.held_out_spec)
      .number("tolerance_m", report.options.tolerance_m)
      .number("min_depth_m", report.options.min_depth_m)
      .number("max_depth_m", report.options.max_depth_m)
      .number("median_abs_residual_m", r.median_abs_residual_m)
      .number("p90_abs_residual_m", r.p90_abs_residual_m)
      .number("mean_abs_residual_m", r.mean_abs_residual_m)
      .number("floating_share", r.floating_share)
      .number("completeness", r.completeness);
  JsonObject pixels;
  pixels.integer("measured", r.total.measured_pixels)
      .integer("mesh", r.total.mesh_pixels)
      .integer("both", r.total.overlap_pixels)
      .integer("agreeing", r.total.agreeing_pixels)
      .integer("floating", r.total.floating_pixels);
  json.object("pixels", pixels)
      .integers("frames_evaluated", r.frames_evaluated)
      .integer("frames_skipped", r.frames_skipped);
  std::vector<JsonObject> per_frame;
  for (size_t i = 0; i < r.per_frame.size(); ++i) {
    const HeldOutCounts& c = r.per_frame[i];
    JsonObject frame;
    frame.integer("frame", r.frames_evaluated[i])
        .number("mean_abs_residual_m",
                c.overlap_pixels == 0 ? NAN : c.abs_residual_sum_m / static_cast<double>(c.overlap_pixels))
        .number("floating_share", share(c.floating_pixels, c.overlap_pixels))
        .number("completeness", share(c.agreeing_pixels, c.measured_pixels))
        .integer("measured_pixels", c.measured_pixels)
        .integer("mesh_pixels", c.mesh_pixels);
    per_frame.push_back(frame);
  }
  json.array("per_frame", per_frame).number("elapsed_s", report.elapsed_s);
  return json.str() + "\n";
}

}  // namespace stereo_fusion::eval
