// Linked into the ThreadSanitizer executables only (test/unit/thread_tests.cmake, and the ROS
// processes of the tsan_ros step in CMakeLists.txt).
// OpenCV runs its parallel loops (scene rendering in the tests, colour conversion) on TBB,
// which is not instrumented: TSan cannot see TBB's synchronisation and reports the handover of
// every loop body as a race. Serial OpenCV keeps TSan looking at our own threads only.
#include <opencv2/core/utility.hpp>

namespace {
const bool kOpenCvSerial = [] {
  cv::setNumThreads(0);  // 0: OpenCV runs everything on the calling thread
  return true;
}();
}  // namespace
