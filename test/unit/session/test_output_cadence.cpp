// OutputCadence: when the node and the offline fuser mesh, update the planning layer and send
// markers — one rule for both, the texture rule included.
#include <gtest/gtest.h>

#include <vector>

#include "stereo_fusion/session/OutputCadence.h"

using namespace stereo_fusion;

namespace {
std::vector<bool> meshedFrames(const OutputCadence& cadence, int frames) {
  std::vector<bool> now;
  for (int n = 1; n <= frames; ++n) now.push_back(cadence.meshTiming(n) == MeshTiming::kNow);
  return now;
}
}  // namespace

TEST(OutputCadence, OfflineMeshesAndPlansAfterEveryNthFusedFrame) {
  const OutputCadence cadence = OutputCadence::everyFrames(3, 2, false);
  EXPECT_EQ(meshedFrames(cadence, 7),
            (std::vector<bool>{false, false, true, false, false, true, false}));
  std::vector<bool> planned;
  for (int n = 1; n <= 5; ++n) planned.push_back(cadence.planningAfterFrame(n));
  EXPECT_EQ(planned, (std::vector<bool>{false, true, false, true, false}));
  EXPECT_EQ(meshedFrames(OutputCadence::everyFrames(1, 10, false), 3),
            (std::vector<bool>{true, true, true}))
      << "--mesh-every 1: after every frame";
  EXPECT_FALSE(OutputCadence::everyFrames(1, 0, false).planningAfterFrame(10))
      << "no planning period: never after a frame";
}

TEST(OutputCadence, TheNodeDefersMeshingToItsRateUnlessTexturesNeedEveryFrame) {
  // A rate: frames are fused deferred, the publisher meshes when due.
  EXPECT_EQ(meshedFrames(OutputCadence::atRates(10.0, 2.0, 1.0, false), 3),
            (std::vector<bool>{false, false, false}));
  // Rate 0: after every frame.
  EXPECT_EQ(meshedFrames(OutputCadence::atRates(0.0, 2.0, 1.0, false), 3),
            (std::vector<bool>{true, true, true}));
  // The texture rule: a patch is cut from the frame of the meshing pass that changed its
  // submesh, so with texture = patches the mesh waits for no rate.
  EXPECT_EQ(meshedFrames(OutputCadence::atRates(10.0, 2.0, 1.0, true), 3),
            (std::vector<bool>{true, true, true}));
  // A period in frames is the fuser's user's explicit choice: kept with textures.
  EXPECT_EQ(meshedFrames(OutputCadence::everyFrames(2, 0, true), 4),
            (std::vector<bool>{false, true, false, true}));
  // The node's planning layer runs on its own timer, never after a frame.
  const OutputCadence node = OutputCadence::atRates(10.0, 2.0, 4.0, false);
  EXPECT_DOUBLE_EQ(node.planningPeriodS(), 0.25);
  EXPECT_FALSE(node.planningAfterFrame(1));
}

TEST(OutputCadence, RateLimitedMeshAndMarkersAreDueOncePerPeriod) {
  OutputCadence cadence = OutputCadence::atRates(10.0, 2.0, 1.0, false);
  EXPECT_TRUE(cadence.meshDue(100.0, false)) << "the first pass is due at once";
  cadence.meshSent(100.0);
  EXPECT_FALSE(cadence.meshDue(100.05, false));
  EXPECT_TRUE(cadence.meshDue(100.1, false));
  EXPECT_FALSE(cadence.meshDue(100.1, true)) << "a frame waiting: the pass may wait a period";
  EXPECT_TRUE(cadence.meshDue(100.2, true));
  cadence.meshSent(100.1);
  EXPECT_FALSE(cadence.meshDue(100.15, false));
  // Markers follow their own rate, not the mesh's.
  EXPECT_TRUE(cadence.markersDue(100.0));
  cadence.markersSent(100.0);
  EXPECT_FALSE(cadence.markersDue(100.3));
  EXPECT_TRUE(cadence.markersDue(100.5));
  // Rate 0: always due.
  OutputCadence every = OutputCadence::atRates(0.0, 0.0, 1.0, false);
  every.meshSent(5.0);
  EXPECT_TRUE(every.meshDue(5.0, true));
  EXPECT_TRUE(every.markersDue(5.0));
}
