// Mapper::disparityNoiseWarning(): the one rule behind the nodelet's and the fuser's warning.
#include <gtest/gtest.h>

#include "MeshTestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {
std::string warningAfterNoisyFrames(double configured_px, double rendered_px) {
  MapperConfig config;
  config.disparity_noise_px = configured_px;
  Mapper mapper(config);
  EXPECT_TRUE(mapper.disparityNoiseWarning().empty()) << "nothing measured yet";
  for (int i = 0; i < 3; ++i) {
    StereoFrame f =
        renderFrame(floorAndSphere(), qvgaCamera(), floorAndSphereView(i), rendered_px, i);
    f.timestamp_s = 1.0 + i;
    EXPECT_TRUE(mapper.integrate(f).accepted);
  }
  return mapper.disparityNoiseWarning();
}
}  // namespace

TEST(DisparityNoiseWarning, SaysSoWhenTheFramesAreNoisierThanConfiguredAndOnlyThen) {
  // Rendered with 0.5 px of noise: measured ~0.5, above 1.5 x 0.15.
  const std::string warning = warningAfterNoisyFrames(0.15, 0.5);
  EXPECT_NE(warning.find("disparity_noise_px is 0.15"), std::string::npos) << warning;
  // Configured as noisy as the frames are: nothing to say.
  EXPECT_EQ(warningAfterNoisyFrames(0.5, 0.5), "");
  // Frames finer than configured: the estimate never says "finer".
  EXPECT_EQ(warningAfterNoisyFrames(0.5, 0.05), "");
}
