// ScopeGuard: the correction's clean-up runs however its scope is left.
#include <gtest/gtest.h>

#include <stdexcept>

#include "stereo_fusion/session/ScopeGuard.h"

using namespace stereo_fusion;

namespace {
int leaveEarly(bool early, int* cleanups) {
  ScopeGuard guard([&] { ++*cleanups; });
  if (early) return 1;
  return 2;
}
}  // namespace

TEST(ScopeGuard, RunsTheCleanUpOnEveryWayOutOnce) {
  int cleanups = 0;
  EXPECT_EQ(leaveEarly(true, &cleanups), 1);
  EXPECT_EQ(cleanups, 1) << "an early return";
  EXPECT_EQ(leaveEarly(false, &cleanups), 2);
  EXPECT_EQ(cleanups, 2) << "the normal end";
  EXPECT_THROW(
      {
        ScopeGuard guard([&] { ++cleanups; });
        throw std::runtime_error("mid re-fusion");
      },
      std::runtime_error);
  EXPECT_EQ(cleanups, 3) << "an exception";
  for (int i = 0; i < 3; ++i) {
    ScopeGuard guard([&] { ++cleanups; });
    if (i == 1) break;
  }
  EXPECT_EQ(cleanups, 5) << "a loop's break, after a full round";
}

TEST(ScopeGuard, RunNowRunsItOnceAndDismissNever) {
  int cleanups = 0;
  {
    ScopeGuard guard([&] { ++cleanups; });
    guard.run();
    EXPECT_EQ(cleanups, 1) << "run(): now";
    guard.run();
  }
  EXPECT_EQ(cleanups, 1) << "not again, neither by run() nor at the scope's end";
  {
    ScopeGuard guard([&] { ++cleanups; });
    guard.dismiss();
  }
  EXPECT_EQ(cleanups, 1) << "dismissed";
}
