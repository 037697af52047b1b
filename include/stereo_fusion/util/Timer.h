#pragma once
#include <chrono>

namespace stereo_fusion {

/// Wall-clock stopwatch for per-stage timings reported to users (never asserted in tests).
class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  double elapsedMs() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_)
        .count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace stereo_fusion
