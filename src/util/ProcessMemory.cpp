#include "stereo_fusion/util/ProcessMemory.h"

#include <cstdio>
#include <cstring>

namespace stereo_fusion {

ProcessMemory readProcessMemory() {
  ProcessMemory m;
  std::FILE* status = std::fopen("/proc/self/status", "r");
  if (status == nullptr) return m;
  const struct {
    const char* key;
    double ProcessMemory::*field;
  } fields[] = {{"VmRSS:", &ProcessMemory::resident_mb},
                {"VmHWM:", &ProcessMemory::peak_resident_mb},
                {"RssAnon:", &ProcessMemory::anonymous_mb},
                {"RssFile:", &ProcessMemory::file_mb}};
  char line[256];
  while (std::fgets(line, sizeof(line), status) != nullptr)
    for (const auto& f : fields) {
      const size_t n = std::strlen(f.key);
      double kib = 0;
      if (std::strncmp(line, f.key, n) == 0 && std::sscanf(line + n, "%lf", &kib) == 1)
        m.*f.field = kib / 1024.0;
    }
  std::fclose(status);
  return m;
}

}  // namespace stereo_fusion
