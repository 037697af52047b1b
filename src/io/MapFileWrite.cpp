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

namespace stereo_fusion {

namespace {
/// Writes all of `bytes` to a new file at `path` and flushes it to the disk (fsync), so that a
/// rename over the old map never leaves an empty or partial file after a power cut.
bool writeDurably(const std::string& path, const std::vector<uint8_t>& bytes, std::string* reason) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    *reason = std::strerror(errno);
    return false;
  }
  size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      *reason = n < 0 ? std::strerror(errno) : "short write";
      ::close(fd);
      return false;
    }
    written += static_cast<size_t>(n);
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
