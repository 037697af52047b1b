#pragma once
// STEREO_FUSION_TEST_QUICK=1 (scripts/check.sh sets it under ThreadSanitizer, which runs the
// code 5-15x slower): the heaviest tests use fewer or smaller inputs. Every check stays the same.
#include <cstdlib>
#include <cstring>

namespace stereo_fusion::test {

inline bool quickMode() {
  const char* value = std::getenv("STEREO_FUSION_TEST_QUICK");
  return value != nullptr && *value != '\0' && std::strcmp(value, "0") != 0;
}

}  // namespace stereo_fusion::test
