#include "stereo_fusion/util/CpuFeatures.h"

namespace stereo_fusion {

bool avx2Supported() {
#if defined(__x86_64__) || defined(__i386__)
  // Normally done by libgcc's constructor; repeated in case a static initialiser asks first.
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2");  // also false when the OS does not save YMM state
#else
  return false;
#endif
}

}  // namespace stereo_fusion
