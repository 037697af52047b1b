#pragma once
#include <functional>
#include <string>

namespace stereo_fusion {

/// Whether `path` may be written: it does not exist yet, or it is a regular file (a symbolic
/// link is judged by what it points to). A FIFO would block the writer until somebody reads it,
/// a device would be written into, a directory cannot be; false with a message naming the path.
bool isWritableTarget(const std::string& path, std::string* error);

/// A fresh temporary name beside `path` (same directory, so a rename onto `path` is atomic),
/// unique per process and per call.
std::string temporaryPathBeside(const std::string& path);

/// Writes `path` whole or not at all: refuses a target that isWritableTarget() refuses, has
/// `write` fill a temporary beside it (false with `*error` set: the temporary is removed) and
/// renames that into place, so a reader never sees half a file and a failure leaves the old one.
/// `what` names the kind of file ("mesh", "map file"). Where the OS will not let the temporary
/// be created: "<path>: cannot write the <what> (<reason>; nothing was written)"; a rename
/// failure: "<path>: cannot write the <what> (rename failed: <reason>)"; a message of `write`
/// that names the temporary names <path> instead.
bool writeThroughTemporary(
    const std::string& path, const std::string& what,
    const std::function<bool(const std::string& temporary_path, std::string* error)>& write,
    std::string* error);

}  // namespace stereo_fusion
