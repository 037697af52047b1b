#pragma once
#include <string>

namespace stereo_fusion {

/// Whether `path` may be written: it does not exist yet, or it is a regular file (a symbolic
/// link is judged by what it points to). A FIFO would block the writer until somebody reads it,
/// a device would be written into, a directory cannot be; false with a message naming the path.
bool isWritableTarget(const std::string& path, std::string* error);

/// A fresh temporary name beside `path` (same directory, so a rename onto `path` is atomic),
/// unique per process and per call.
std::string temporaryPathBeside(const std::string& path);

}  // namespace stereo_fusion
