#include <gtest/gtest.h>

#include <cstring>
#include <memory>

#include "stereo_fusion/util/ProcessMemory.h"

namespace stereo_fusion {
namespace {

TEST(ProcessMemory, SeesTouchedHeapAsAnonymousAndResident) {
  const ProcessMemory before = readProcessMemory();
  ASSERT_GT(before.resident_mb, 0.0) << "/proc/self/status unreadable";
  EXPECT_GT(before.file_mb, 0.0);  // the test binary's own code is a file's pages
  EXPECT_GE(before.peak_resident_mb, before.resident_mb);
  constexpr size_t kBytes = 64u << 20;
  std::unique_ptr<char[]> block(new char[kBytes]);
  std::memset(block.get(), 1, kBytes);  // touched: resident
  // The buffer escapes: a compiler may not drop the allocation and fold the read below.
  asm volatile("" : : "r"(block.get()) : "memory");
  const ProcessMemory after = readProcessMemory();
  EXPECT_EQ(block[kBytes / 2], 1);
  EXPECT_GT(after.resident_mb - before.resident_mb, 60.0);
  EXPECT_GT(after.anonymous_mb - before.anonymous_mb, 60.0);
  EXPECT_GE(after.peak_resident_mb, after.resident_mb);
  EXPECT_NEAR(after.resident_mb, after.anonymous_mb + after.file_mb, 64.0 / 1024 + 1.0);
}

}  // namespace
}  // namespace stereo_fusion
