#pragma once
#include <cstdint>
#include <vector>

#include "stereo_fusion/map/BlockKey.h"

namespace stereo_fusion {

/// A set of block keys within a known box, one bit per block of the box: inserting is an index
/// and an OR, and the keys are read back by walking the bits in z, y, x order, which is
/// BlockKey's sort order, so the set comes out sorted without a sort. For de-duplicating one
/// pass's keys when their bounding box is small (a frame's blocks lie in the camera frustum:
/// ~10^5 blocks of box for ~5 000 keys), reused pass after pass. BlockKeySet is the general case.
class BlockKeyBitmap {
 public:
  /// Largest box (in bits, rows rounded up to 64) reset() accepts: 2 MiB of bitmap.
  static constexpr int64_t kMaxBits = int64_t{1} << 24;

  /// Empties the set for keys within [lo, hi] (inclusive on every axis). False, leaving the set
  /// unusable until the next reset(), if the box is empty or needs more than kMaxBits bits.
  bool reset(const BlockKey& lo, const BlockKey& hi) {
    const int64_t nx = int64_t{hi.x} - lo.x + 1, ny = int64_t{hi.y} - lo.y + 1,
                  nz = int64_t{hi.z} - lo.z + 1;
    if (nx <= 0 || ny <= 0 || nz <= 0) return false;
    // Each (y, z) row starts on a word, so reading back needs no division.
    const int64_t words_per_row = (nx + 63) / 64;
    if (words_per_row * 64 > kMaxBits / ny / nz) return false;
    lo_ = lo;
    ny_ = static_cast<int32_t>(ny);
    nz_ = static_cast<int32_t>(nz);
    words_per_row_ = static_cast<int32_t>(words_per_row);
    words_.assign(static_cast<size_t>(words_per_row * ny * nz), 0);
    return true;
  }

  /// Adds `key`, which must lie within the box given to reset().
  void insert(const BlockKey& key) {
    const uint32_t x = static_cast<uint32_t>(key.x - lo_.x);
    const size_t row =
        static_cast<size_t>(key.z - lo_.z) * ny_ + static_cast<size_t>(key.y - lo_.y);
    words_[row * words_per_row_ + x / 64] |= uint64_t{1} << (x % 64);
  }

  /// Appends the set's keys to `keys` in ascending BlockKey order.
  void appendSorted(std::vector<BlockKey>* keys) const {
    const uint64_t* word = words_.data();
    for (int32_t z = 0; z < nz_; ++z)
      for (int32_t y = 0; y < ny_; ++y)
        for (int32_t w = 0; w < words_per_row_; ++w, ++word)
          for (uint64_t bits = *word; bits != 0; bits &= bits - 1)
            keys->push_back({lo_.x + w * 64 + __builtin_ctzll(bits), lo_.y + y, lo_.z + z});
  }

 private:
  BlockKey lo_;
  int32_t ny_ = 0, nz_ = 0, words_per_row_ = 0;
  std::vector<uint64_t> words_;
};

}  // namespace stereo_fusion
