#pragma once
// Helpers shared by the fuzz targets: reading typed values from the fuzzer's bytes, and one
// scratch folder per process for the readers that only take file paths.

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion::fuzz {

/// Consumes the input front to back. Past the end every value reads as zero, so a short input
/// is simply a frame full of defaults, never an out-of-bounds read.
class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  size_t remaining() const { return size_ - pos_; }
  uint8_t u8() { return pos_ < size_ ? data_[pos_++] : 0; }
  /// A raw IEEE float: every bit pattern, NaN, infinities and subnormals included.
  float f32() {
    uint32_t bits = 0;
    for (int i = 0; i < 4; ++i) bits |= static_cast<uint32_t>(u8()) << (8 * i);
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  }
  /// `lo` + (byte / 255) · (hi − lo): a plausible value, so most inputs reach the deep code.
  double scaled(double lo, double hi) { return lo + (hi - lo) * u8() / 255.0; }
  /// The rest of the input up to the next `separator` (consumed, not returned).
  std::string section(const std::string& separator) {
    const char* begin = reinterpret_cast<const char*>(data_) + pos_;
    const std::string rest(begin, remaining());
    const size_t end = rest.find(separator);
    if (end == std::string::npos) {
      pos_ = size_;
      return rest;
    }
    pos_ += end + separator.size();
    return rest.substr(0, end);
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

/// A private folder for this process (libFuzzer's -jobs/-fork run several), removed at a normal
/// exit. libFuzzer itself ends with _Exit(), which skips that: scripts/fuzz.sh points TMPDIR at
/// a folder of its own and removes it after the run.
class ScratchDir {
 public:
  ScratchDir() {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base && *base ? base : "/tmp") + "/stereo_fusion_fuzz_XXXXXX";
    if (!mkdtemp(pattern.data())) std::abort();
    path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

inline const std::filesystem::path& scratchDir() {
  static const ScratchDir dir;
  return dir.path();
}

inline void writeFile(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) std::abort();  // the scratch folder is ours: failing to write it is a harness bug
}

/// Aborts (a finding) when an invariant of the code under test does not hold.
inline void require(bool condition) {
  if (!condition) std::abort();
}

/// The mesh invariants every target that fuses checks: finite vertices and normals, one normal
/// per vertex, every triangle indexing a vertex.
inline void checkMesh(const TriangleMesh& mesh) {
  require(mesh.normals.size() == mesh.positions.size());
  for (const auto& p : mesh.positions) require(p.allFinite());
  for (const auto& n : mesh.normals) require(n.allFinite());
  for (const auto& t : mesh.triangles)
    for (uint32_t i : t) require(i < mesh.positions.size());
}

}  // namespace stereo_fusion::fuzz
