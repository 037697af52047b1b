// Writing map file bytes to the disk durably; the format itself is MapFile.cpp's.
#include "stereo_fusion/io/MapFile.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <vector>

#include "stereo_fusion/io/WriteTarget.h"
#include "stereo_fusion/util/Crc32.h"

namespace stereo_fusion {

namespace {
/// Writes all of `size` bytes at the file's position; false with `reason` on an error.
bool writeAll(int fd, const uint8_t* data, size_t size, std::string* reason) {
  size_t written = 0;
  while (written < size) {
    const ssize_t n = ::write(fd, data + written, size - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      *reason = n < 0 ? std::strerror(errno) : "short write";
      return false;
    }
    written += static_cast<size_t>(n);
  }
  return true;
}

/// Writes all of `bytes` to a new file at `path` and flushes it to the disk (fsync), so that a
/// rename over the old map never leaves an empty or partial file after a power cut.
bool writeDurably(const std::string& path, const std::vector<uint8_t>& bytes, std::string* reason) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    *reason = std::strerror(errno);
    return false;
  }
  if (!writeAll(fd, bytes.data(), bytes.size(), reason)) {
    ::close(fd);
    return false;
  }
  if (::fsync(fd) != 0) {
    *reason = std::string("fsync: ") + std::strerror(errno);
    ::close(fd);
    return false;
  }
  if (::close(fd) != 0) {
    *reason = std::strerror(errno);
    return false;
  }
  return true;
}

/// Appends bytes to a file through a buffer, keeping the CRC-32 of everything after the header.
class BufferedFile {
 public:
  explicit BufferedFile(int fd) : fd_(fd) { buffer_.reserve(kBufferBytes); }
  bool append(const uint8_t* data, size_t size) {
    crc_ = crc32(data, size, crc_);
    bytes_ += size;
    buffer_.insert(buffer_.end(), data, data + size);
    return buffer_.size() < kBufferBytes || flush();
  }
  bool flush() {
    if (!writeAll(fd_, buffer_.data(), buffer_.size(), &reason_)) return false;
    buffer_.clear();
    return true;
  }
  uint32_t crc() const { return crc_; }
  uint64_t bytes() const { return bytes_; }
  const std::string& reason() const { return reason_; }

 private:
  static constexpr size_t kBufferBytes = 1 << 20;
  int fd_;
  std::vector<uint8_t> buffer_;
  uint32_t crc_ = 0;
  uint64_t bytes_ = 0;
  std::string reason_;
};

/// Flushes the directory holding `path`, so that a rename into it is on the disk too (best
/// effort: some file systems refuse fsync on directories, and the file itself is already safe).
void syncParentDirectory(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const std::string dir =
      slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}
}  // namespace

bool writeMapFile(const std::string& path, const MapperConfig& config, uint64_t frames_integrated,
                  uint64_t block_count, const MapFileBlocks& blocks,
                  const SeenFreeSpace& free_space, std::string* error) {
  const bool written = writeThroughTemporary(
      path, "map file",
      [&](const std::string& temporary, std::string* why) {
        const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (fd < 0) {
          *why = path + ": cannot write the map file (" + std::strerror(errno) + ")";
          return false;
        }
        std::string reason;
        uint8_t header[kMapFileHeaderBytes] = {};
        bool ok = ::lseek(fd, kMapFileHeaderBytes, SEEK_SET) == kMapFileHeaderBytes;
        if (!ok) reason = std::strerror(errno);
        BufferedFile out(fd);
        uint64_t count = 0;
        std::vector<uint8_t> record;
        std::string read_error;
        ok = ok && blocks(
                       [&](const VoxelBlock& block, uint64_t last_update_frame) {
                         record.resize(mapFileRecordBytes(block));
                         encodeMapFileRecord(block, last_update_frame, record.data());
                         ok = ok && out.append(record.data(), record.size());
                         ++count;
                       },
                       &read_error);
        if (!read_error.empty()) reason = read_error;
        if (ok && count != block_count) {
          ok = false;
          reason =
              std::to_string(count) + " blocks read, " + std::to_string(block_count) + " announced";
        }
        if (ok) {
          record.resize(mapFileFreeSpaceBytes(free_space));
          encodeMapFileFreeSpace(free_space, record.data());
          ok = out.append(record.data(), record.size()) && out.flush();
        }
        if (ok) {
          encodeMapFileHeader(config, frames_integrated, block_count, out.bytes(), header);
          sealMapFileHeader(header, out.crc());
          ok = ::pwrite(fd, header, sizeof(header), 0) == static_cast<ssize_t>(sizeof(header));
          if (!ok) reason = std::strerror(errno);
        }
        if (ok && ::fsync(fd) != 0) {
          ok = false;
          reason = std::string("fsync: ") + std::strerror(errno);
        }
        if (reason.empty() && !out.reason().empty()) reason = out.reason();
        if (::close(fd) != 0 && ok) {
          ok = false;
          reason = std::strerror(errno);
        }
        if (!ok) *why = path + ": cannot write the map file (" + reason + ")";
        return ok;
      },
      error);
  if (written) syncParentDirectory(path);
  return written;
}

bool writeMapFileBytes(const std::string& path, std::vector<uint8_t>* bytes, std::string* error) {
  sealMapFile(bytes);
  // The temporary is unique per process and per call, so saves to one path from several threads
  // (or nodelets of one manager) never share one; the last rename wins, whole.
  const bool written = writeThroughTemporary(
      path, "map file",
      [&](const std::string& temporary, std::string* why) {
        std::string reason;
        if (writeDurably(temporary, *bytes, &reason)) return true;
        *why = path + ": cannot write the map file (" + reason + ")";
        return false;
      },
      error);
  if (written) syncParentDirectory(path);
  return written;
}

}  // namespace stereo_fusion
