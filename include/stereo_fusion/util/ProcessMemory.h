#pragma once

namespace stereo_fusion {

/// This process's resident memory from /proc/self/status (Linux), in MiB; zeros elsewhere.
struct ProcessMemory {
  double resident_mb = 0;       ///< VmRSS
  double peak_resident_mb = 0;  ///< VmHWM: the most resident at any time so far
  double anonymous_mb = 0;      ///< RssAnon: the heap, thread arenas and stacks
  double file_mb = 0;           ///< RssFile: pages of the program's and its libraries' files
};

ProcessMemory readProcessMemory();

}  // namespace stereo_fusion
