#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <deque>

namespace stereo_fusion {

/// The stamps (ns) one topic passed to the synchroniser whose frame is not matched yet (at most
/// the last `capacity`), so that a second message of such a stamp is held back. message_filters'
/// ExactTime policy keeps one message per topic and stamp and lets a second one replace the
/// first while the set is incomplete: a corrupt copy arriving right after a good message would
/// be fused and the good one lost. Here the first message of a stamp wins. Once the frame is
/// matched (forget()), a repeat reaches the synchroniser as a new set and the frame gate rejects
/// it as a duplicate frame.
class RecentStamps {
 public:
  explicit RecentStamps(size_t capacity) : capacity_(capacity < 1 ? 1 : capacity) {}

  /// True (and remembered) if `stamp_ns` is not among the stamps held.
  bool pass(uint64_t stamp_ns) {
    if (std::find(stamps_.begin(), stamps_.end(), stamp_ns) != stamps_.end()) return false;
    stamps_.push_back(stamp_ns);
    if (stamps_.size() > capacity_) stamps_.pop_front();  // its set was never completed
    return true;
  }

  /// The frame of `stamp_ns` was matched: a later message of that stamp is a new set.
  void forget(uint64_t stamp_ns) {
    stamps_.erase(std::remove(stamps_.begin(), stamps_.end(), stamp_ns), stamps_.end());
  }

 private:
  size_t capacity_;
  std::deque<uint64_t> stamps_;
};

}  // namespace stereo_fusion
