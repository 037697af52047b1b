#pragma once
#include <utility>

namespace stereo_fusion {

/// Runs a clean-up when the scope it guards is left, whichever way: a return, a break or an
/// exception (a correction's unpinning of the timeline, which used to be written at each exit).
/// run() runs it now instead (once); dismiss() keeps it from running.
template <typename F>
class ScopeGuard {
 public:
  explicit ScopeGuard(F cleanup) : cleanup_(std::move(cleanup)) {}
  ~ScopeGuard() {
    if (active_) cleanup_();
  }
  ScopeGuard(const ScopeGuard&) = delete;
  ScopeGuard& operator=(const ScopeGuard&) = delete;
  void run() {
    if (active_) cleanup_();
    active_ = false;
  }
  void dismiss() { active_ = false; }

 private:
  F cleanup_;
  bool active_ = true;
};

}  // namespace stereo_fusion
