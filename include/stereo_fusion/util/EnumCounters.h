#pragma once
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace stereo_fusion {

/// One counter per value of an enum whose values run 0 … N − 1, safe to bump from any thread
/// (the frames' reject reasons, the trajectories' outcomes).
template <typename Enum, size_t N>
class EnumCounters {
 public:
  void count(Enum value, uint64_t n = 1) { counts_[static_cast<size_t>(value)] += n; }
  uint64_t operator[](Enum value) const { return counts_[static_cast<size_t>(value)].load(); }
  /// Calls f(value, count) for every value, in order.
  template <typename F>
  void forEachValue(F&& f) const {
    for (size_t k = 0; k < N; ++k) f(static_cast<Enum>(k), counts_[k].load());
  }

 private:
  std::array<std::atomic<uint64_t>, N> counts_{};
};

/// True if row k of `table` (rows with a member `key` of the enum's type) describes value k:
/// a table of names checked against its enum at compile time.
template <typename Row, size_t N, typename Enum>
constexpr bool rowsFollowEnum(const Row (&table)[N], Enum Row::*key) {
  for (size_t k = 0; k < N; ++k)
    if (static_cast<size_t>(table[k].*key) != k) return false;
  return true;
}

}  // namespace stereo_fusion
