#include "stereo_fusion/session/InputHealth.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace stereo_fusion {

std::vector<std::string> validateInputHealthConfig(const InputHealthConfig& config) {
  std::vector<std::string> errors;
  if (!(std::isfinite(config.window_s) && config.window_s > 0.0))
    errors.push_back("diagnostics_window_s must be a finite number of seconds > 0");
  if (!(std::isfinite(config.input_timeout_s) && config.input_timeout_s >= 0.0))
    errors.push_back("input_timeout_s must be a finite number of seconds >= 0 (0 = off)");
  if (config.measurement.empty() || config.measurements.empty())
    errors.push_back("the measurements' names must not be empty");
  return errors;
}

void InputHealth::sample(double now_s, const InputTotals& read) {
  InputTotals totals = read;
  if (samples_.empty()) {
    // Whatever the first reading holds arrived before it.
    if (totals.frames > 0) last_frame_change_s_ = now_s;
    if (totals.disparities > 0) last_disparity_change_s_ = now_s;
  } else {
    const InputTotals& before = samples_.back().totals;
    totals.disparities = std::max(totals.disparities, before.disparities);
    totals.frames = std::max(totals.frames, before.frames);
    totals.dropped = std::max(totals.dropped, before.dropped);
    if (totals.frames > before.frames) last_frame_change_s_ = now_s;
    if (totals.disparities > before.disparities) last_disparity_change_s_ = now_s;
  }
  samples_.push_back({now_s, totals});
  // Keep one sample at or before the window's start: the baseline the differences start from.
  while (samples_.size() >= 2 && samples_[1].t_s <= now_s - config_.window_s) samples_.pop_front();
}

InputWindowReport InputHealth::report() const {
  InputWindowReport r;
  if (samples_.empty()) return r;
  const Sample& base = samples_.front();
  const Sample& newest = samples_.back();
  r.span_s = newest.t_s - base.t_s;
  if (r.span_s > 0.0) {
    r.disparities_per_s = (newest.totals.disparities - base.totals.disparities) / r.span_s;
    r.frames_per_s = (newest.totals.frames - base.totals.frames) / r.span_s;
  }
  r.dropped = newest.totals.dropped - base.totals.dropped;
  r.first_frame_seen = last_frame_change_s_ >= 0.0;
  if (!r.first_frame_seen) return r;
  r.since_last_frame_s = newest.t_s - last_frame_change_s_;
  const double timeout_s = config_.input_timeout_s;
  r.stale = timeout_s > 0.0 && r.since_last_frame_s >= timeout_s;
  r.disparities_arriving = r.stale && last_disparity_change_s_ >= 0.0 &&
                           newest.t_s - last_disparity_change_s_ < timeout_s;
  return r;
}

std::string InputHealth::staleMessage() const {
  const InputWindowReport r = report();
  if (!r.stale) return "";
  char text[128];
  std::snprintf(text, sizeof(text), "input stale: no frame for %.1f s (input_timeout_s %g); ",
                r.since_last_frame_s, config_.input_timeout_s);
  return text +
         (r.disparities_arriving
              ? config_.measurements +
                    " still arrive: their image or camera_info stopped or no longer matches"
              : "no " + config_.measurement + " either: has the camera or its driver stopped?");
}

}  // namespace stereo_fusion
