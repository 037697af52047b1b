#pragma once
#include <cstdint>

namespace stereo_fusion {

/// Counts messages lost before they reached a subscriber, from the gaps in their header.seq:
/// what a publisher's or subscriber's queue discarded in the transport, or a driver skipped.
/// roscpp numbers every message a publisher sends to another process (0, 1, 2, …, per
/// publisher); rosbag play keeps the recorded numbers. A number that does not follow the
/// previous one by at most kMaxGap + 1 (a repeat, a publisher restarted at 0, another publisher,
/// a bag recorded with every seq 0) starts a new count without a gap; 2³² − 1 → 0 is a wrap.
class SequenceGaps {
 public:
  static constexpr uint32_t kMaxGap = 100000;

  /// The number of messages missing between the previous message and this one (0 if none).
  uint64_t next(uint32_t seq) {
    const bool first = !have_last_;
    const uint32_t gap = seq - last_ - 1;  // modulo 2³²: a wrap is a gap of 0
    have_last_ = true;
    last_ = seq;
    return !first && gap <= kMaxGap ? gap : 0;
  }

 private:
  bool have_last_ = false;
  uint32_t last_ = 0;
};

}  // namespace stereo_fusion
