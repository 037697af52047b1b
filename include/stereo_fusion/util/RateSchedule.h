#pragma once
#include <limits>

namespace stereo_fusion {

/// When an output limited to a rate is next due, for a caller that can only send when it gets
/// the chance (after a frame is fused). Each send is due one period after the previous send was
/// *due*, not after it happened: the chances come late by up to a frame, and a period counted
/// from the send would add that lateness to every period (at 10 Hz with frames every 33 ms,
/// meshes came every 3.4 frames, 8.9 Hz). On average at most `rate_hz`; a send late by more
/// than half a period starts the schedule again from it, so two sends are never closer than
/// half a period.
class RateSchedule {
 public:
  /// `rate_hz` ≤ 0: always due.
  explicit RateSchedule(double rate_hz) : period_s_(rate_hz > 0.0 ? 1.0 / rate_hz : 0.0) {}

  /// `may_wait`: the caller would rather send a little later (more is coming that the send
  /// should carry); it is then due a period later, so it is put off at most that long.
  bool due(double now_s, bool may_wait = false) const {
    return period_s_ <= 0.0 || now_s >= next_s_ + (may_wait ? period_s_ : 0.0);
  }

  /// A send at `now_s` that was due (one out of turn, forced, leaves the schedule as it was).
  void sent(double now_s) {
    next_s_ += period_s_;
    if (!(next_s_ >= now_s + 0.5 * period_s_)) next_s_ = now_s + period_s_;
  }

 private:
  double period_s_;
  double next_s_ = -std::numeric_limits<double>::infinity();
};

}  // namespace stereo_fusion
