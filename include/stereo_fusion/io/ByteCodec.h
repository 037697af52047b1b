#pragma once
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace stereo_fusion {

// Pages (paging/BlockPage) are machine-local scratch and copy numbers as they lie in memory.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "byte codec assumes little-endian");

/// Appends plain values and arrays to a byte buffer (a block's page).
class ByteWriter {
 public:
  explicit ByteWriter(std::vector<uint8_t>* out) : out_(out) {}
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>, "plain values only");
    putBytes(&value, sizeof(T));
  }
  /// A count (u64) then the elements (plain data: numbers, std::array, Eigen's fixed sizes).
  template <typename T>
  void putArray(const std::vector<T>& values) {
    put<uint64_t>(values.size());
    if (!values.empty()) putBytes(values.data(), values.size() * sizeof(T));
  }
  void putBytes(const void* data, size_t bytes) {
    const auto* p = static_cast<const uint8_t*>(data);
    out_->insert(out_->end(), p, p + bytes);
  }
  size_t size() const { return out_->size(); }
  std::vector<uint8_t>& buffer() { return *out_; }

 private:
  std::vector<uint8_t>* out_;
};

/// Reads what a ByteWriter wrote; every read is bounds-checked and a short or oversized read
/// makes ok() false (and reads zeros) instead of reading past the end.
class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : p_(data), end_(data + size) {}
  template <typename T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>, "plain values only");
    T value{};
    getBytes(&value, sizeof(T));
    return value;
  }
  /// An array written by putArray(); at most `max_count` elements (a corrupted count is refused).
  template <typename T>
  bool getArray(std::vector<T>* values, size_t max_count) {
    const uint64_t n = get<uint64_t>();
    if (!ok_ || n > max_count || n * sizeof(T) > remaining()) return fail();
    values->resize(n);
    if (n > 0) getBytes(values->data(), n * sizeof(T));
    return ok_;
  }
  void getBytes(void* data, size_t bytes) {
    if (bytes > remaining()) {
      fail();
      std::memset(data, 0, bytes);
      return;
    }
    std::memcpy(data, p_, bytes);
    p_ += bytes;
  }
  void skip(size_t bytes) {
    if (bytes > remaining()) {
      fail();
      return;
    }
    p_ += bytes;
  }
  size_t remaining() const { return static_cast<size_t>(end_ - p_); }
  const uint8_t* position() const { return p_; }
  bool ok() const { return ok_; }
  bool fail() {
    ok_ = false;
    p_ = end_;
    return false;
  }

 private:
  const uint8_t* p_;
  const uint8_t* end_;
  bool ok_ = true;
};

}  // namespace stereo_fusion
