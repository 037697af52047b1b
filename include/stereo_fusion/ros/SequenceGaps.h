#pragma once
#include <cstdint>

namespace stereo_fusion {

/// Counts messages lost before they reached a subscriber, from the gaps in their header.seq:
/// what a publisher's or subscriber's queue discarded in the transport, or a driver skipped.
/// A stream that does not number its messages (seq always 0, as roscpp leaves it) counts
/// nothing; a number that goes back (the publisher restarted, or a reordering) or jumps by more
/// than kMaxGap (a different publisher) starts a new count without a gap.
class SequenceGaps {
 public:
  static constexpr uint32_t kMaxGap = 100000;

  /// The number of messages missing between the previous message and this one (0 if none).
  uint64_t next(uint32_t seq) {
    const uint32_t last = last_;
    last_ = seq;
    if (seq == 0 || last == 0 || seq <= last) return 0;
    const uint32_t gap = seq - last - 1;
    return gap <= kMaxGap ? gap : 0;
  }

 private:
  uint32_t last_ = 0;  // 0: no numbered message yet
};

}  // namespace stereo_fusion
