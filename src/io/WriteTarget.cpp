#include "stereo_fusion/io/WriteTarget.h"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace stereo_fusion {

bool isWritableTarget(const std::string& path, std::string* error) {
  struct stat st;
  // Absent (or not reachable): the writer creates it, or fails with its own message.
  if (::stat(path.c_str(), &st) != 0) return true;
  if (S_ISREG(st.st_mode)) return true;
  const char* kind = S_ISFIFO(st.st_mode)                         ? "a FIFO"
                     : S_ISDIR(st.st_mode)                        ? "a directory"
                     : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device"
                     : S_ISSOCK(st.st_mode)                       ? "a socket"
                                                                  : "not a regular file";
  *error = path + " is " + kind + ": only regular files are written (nothing was written)";
  return false;
}

std::string temporaryPathBeside(const std::string& path) {
  static std::atomic<uint64_t> count{0};
  return path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(count++);
}

bool writeThroughTemporary(
    const std::string& path, const std::string& what,
    const std::function<bool(const std::string& temporary_path, std::string* error)>& write,
    std::string* error) {
  if (!isWritableTarget(path, error)) return false;
  const std::string temporary = temporaryPathBeside(path);
  // Created here first, so that a folder the user may not write to is refused with the OS's
  // cause and the user's own path, not a writer's message about an internal temporary name.
  std::FILE* probe = std::fopen(temporary.c_str(), "wb");
  if (probe == nullptr) {
    *error = path + ": cannot write the " + what + " (" + std::strerror(errno) +
             "; nothing was written)";
    return false;
  }
  std::fclose(probe);
  if (!write(temporary, error)) {
    std::remove(temporary.c_str());
    // A writer names the file it wrote: the temporary. The user gave `path`.
    for (size_t at = error->find(temporary); at != std::string::npos;
         at = error->find(temporary, at + path.size()))
      error->replace(at, temporary.size(), path);
    return false;
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    *error = path + ": cannot write the " + what + " (rename failed: " + std::strerror(errno) + ")";
    std::remove(temporary.c_str());
    return false;
  }
  return true;
}

}  // namespace stereo_fusion
