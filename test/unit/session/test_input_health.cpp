// InputHealth: rates and drops over a sliding window and stale input, on a clock the test
// drives (a sample a second, as the node's diagnostics take them), with hand-worked numbers.
#include <gtest/gtest.h>

#include <cmath>

#include "stereo_fusion/session/InputHealth.h"

using namespace stereo_fusion;

namespace {

InputHealth withWindow(double window_s, double timeout_s) {
  InputHealthConfig config;
  config.window_s = window_s;
  config.input_timeout_s = timeout_s;
  return InputHealth(config);
}

}  // namespace

// 10 frames/s for 10 s, then 20/s. At t = 15 the window is [5, 15]: frames 50 → 200, 15 Hz
// (the average since start would be 200 / 15 = 13.3 Hz).
TEST(InputHealth, RatesCoverTheWindowNotTheRunSinceStart) {
  InputHealth health = withWindow(10.0, 2.0);
  for (int t = 0; t <= 15; ++t) {
    const uint64_t frames = t <= 10 ? 10 * t : 100 + 20 * (t - 10);
    health.sample(t, {frames + 1, frames, 0});  // one disparity more: waiting for its image
  }
  const InputWindowReport r = health.report();
  EXPECT_DOUBLE_EQ(r.span_s, 10.0);
  EXPECT_DOUBLE_EQ(r.frames_per_s, 15.0);
  EXPECT_DOUBLE_EQ(r.disparities_per_s, 15.0);
  EXPECT_EQ(r.dropped, 0u);
}

// Before the samples reach back a whole window, the figures cover what they do reach.
TEST(InputHealth, AtStartTheSpanIsWhatTheSamplesCover) {
  InputHealth health = withWindow(10.0, 2.0);
  EXPECT_DOUBLE_EQ(health.report().span_s, 0.0) << "no sample yet";
  health.sample(100.0, {0, 0, 0});
  EXPECT_DOUBLE_EQ(health.report().frames_per_s, 0.0) << "one sample: no span, no rate";
  health.sample(104.0, {12, 12, 3});
  const InputWindowReport r = health.report();
  EXPECT_DOUBLE_EQ(r.span_s, 4.0);
  EXPECT_DOUBLE_EQ(r.frames_per_s, 3.0);
  EXPECT_EQ(r.dropped, 3u);
}

// Two drops between t = 2 and t = 3: in the window (WARN) up to t = 12, out of it from t = 13,
// while the total since start stays the caller's.
TEST(InputHealth, DropsLeaveTheWindowOnceItHasPassedThem) {
  InputHealth health = withWindow(10.0, 2.0);
  std::vector<uint64_t> dropped_in_window;
  for (int t = 0; t <= 14; ++t) {
    health.sample(t, {10u * t, 10u * t, t >= 3 ? 2u : 0u});
    dropped_in_window.push_back(health.report().dropped);
  }
  EXPECT_EQ(dropped_in_window,
            (std::vector<uint64_t>{0, 0, 0, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 0, 0}));
}

// A total read smaller than before (the synchroniser's estimate of lost disparities falls back
// when late parts match) counts as the largest before it: 5, 3, 6 is one new drop, not three.
TEST(InputHealth, ATotalThatFallsBackIsNoNewDrop) {
  InputHealth health = withWindow(10.0, 0.0);
  health.sample(0.0, {0, 0, 5});
  health.sample(1.0, {0, 0, 3});
  EXPECT_EQ(health.report().dropped, 0u);
  health.sample(2.0, {0, 0, 6});
  EXPECT_EQ(health.report().dropped, 1u);
}

// Frames until the sample at t = 5, then none: 1 s without at t = 6, 2 s (the timeout) at t = 7:
// stale; frames again at t = 9: not stale.
TEST(InputHealth, InputIsStaleAfterTheTimeoutWithoutAFrameAndRecovers) {
  InputHealth health = withWindow(10.0, 2.0);
  const uint64_t frames_at[] = {0, 5, 10, 15, 20, 25, 25, 25, 25, 30};
  std::vector<bool> stale;
  for (int t = 0; t <= 9; ++t) {
    health.sample(t, {frames_at[t], frames_at[t], 0});
    stale.push_back(health.report().stale);
    if (t == 7) {
      EXPECT_DOUBLE_EQ(health.report().since_last_frame_s, 2.0);
      EXPECT_FALSE(health.report().disparities_arriving);
      const std::string message = health.staleMessage();
      EXPECT_NE(message.find("input stale: no frame for 2.0 s (input_timeout_s 2)"),
                std::string::npos)
          << message;
      EXPECT_NE(message.find("no disparity either"), std::string::npos) << message;
    }
  }
  EXPECT_EQ(stale, (std::vector<bool>{false, false, false, false, false, false, false, true, true,
                                      false}));
  EXPECT_DOUBLE_EQ(health.report().since_last_frame_s, 0.0);
  EXPECT_TRUE(health.staleMessage().empty());
}

// A node started before its camera is waiting, not stale, however long it waits.
TEST(InputHealth, NothingIsStaleBeforeTheFirstFrame) {
  InputHealth health = withWindow(10.0, 2.0);
  for (int t = 0; t <= 100; ++t) health.sample(t, {0, 0, 0});
  const InputWindowReport r = health.report();
  EXPECT_FALSE(r.first_frame_seen);
  EXPECT_FALSE(r.stale);
  EXPECT_TRUE(std::isnan(r.since_last_frame_s));
  // Frames counted before the first sample arrived before it.
  InputHealth late = withWindow(10.0, 2.0);
  late.sample(50.0, {3, 3, 0});
  late.sample(52.5, {3, 3, 0});
  EXPECT_TRUE(late.report().first_frame_seen);
  EXPECT_DOUBLE_EQ(late.report().since_last_frame_s, 2.5);
  EXPECT_TRUE(late.report().stale);
}

// Disparities that keep coming while no frame is matched point at the image or camera_info.
TEST(InputHealth, StaleFramesWithDisparitiesStillArrivingSaySo) {
  InputHealth health = withWindow(10.0, 2.0);
  health.sample(0.0, {10, 10, 0});
  health.sample(1.0, {20, 10, 0});
  health.sample(2.0, {30, 10, 0});
  ASSERT_TRUE(health.report().stale);
  EXPECT_TRUE(health.report().disparities_arriving);
  EXPECT_NE(health.staleMessage().find("disparities still arrive"), std::string::npos)
      << health.staleMessage();
}

// input: depth: the message names depth images, whichever way the input went stale.
TEST(InputHealth, StaleMessagesNameTheMeasurementsTheyCount) {
  InputHealthConfig config;
  config.window_s = 10.0;
  config.input_timeout_s = 2.0;
  config.measurement = "depth image";
  config.measurements = "depth images";
  InputHealth arriving(config), stopped(config);
  for (int k = 0; k < 3; ++k) {
    arriving.sample(k, {10u + 10u * k, 10, 0});
    stopped.sample(k, {10, 10, 0});
  }
  ASSERT_TRUE(arriving.report().stale && stopped.report().stale);
  EXPECT_NE(arriving.staleMessage().find("depth images still arrive"), std::string::npos)
      << arriving.staleMessage();
  EXPECT_NE(stopped.staleMessage().find("no depth image either"), std::string::npos)
      << stopped.staleMessage();
  EXPECT_EQ(arriving.staleMessage().find("disparit"), std::string::npos) << arriving.staleMessage();
  EXPECT_EQ(stopped.staleMessage().find("disparit"), std::string::npos) << stopped.staleMessage();
}

TEST(InputHealth, TimeoutZeroTurnsTheCheckOff) {
  InputHealth health = withWindow(10.0, 0.0);
  health.sample(0.0, {1, 1, 0});
  health.sample(1000.0, {1, 1, 0});
  EXPECT_FALSE(health.report().stale);
  EXPECT_DOUBLE_EQ(health.report().since_last_frame_s, 1000.0);
}

TEST(InputHealth, ConfigValidation) {
  EXPECT_TRUE(validateInputHealthConfig(InputHealthConfig{}).empty());
  EXPECT_TRUE(validateInputHealthConfig({1.0, 0.0}).empty()) << "timeout 0: off";
  EXPECT_EQ(validateInputHealthConfig({0.0, 2.0}).size(), 1u);
  EXPECT_EQ(validateInputHealthConfig({-1.0, 2.0}).size(), 1u);
  EXPECT_EQ(validateInputHealthConfig({NAN, 2.0}).size(), 1u);
  EXPECT_EQ(validateInputHealthConfig({10.0, -0.5}).size(), 1u);
  EXPECT_EQ(validateInputHealthConfig({10.0, INFINITY}).size(), 1u);
  InputHealthConfig unnamed;
  unnamed.measurements = "";
  EXPECT_EQ(validateInputHealthConfig(unnamed).size(), 1u);
}
