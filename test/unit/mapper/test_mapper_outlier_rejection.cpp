// The Mapper applies OutlierRejection between the coherence check and the lookup: rejected
// pixels are counted in IntegrationResult and are missing from what the lookup saw.
#include <gtest/gtest.h>

#include "MeshTestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

TEST(MapperOutlierRejection, RejectedPixelsAreCountedAndNotLookedUp) {
  // The sphere in front of the floor: its silhouette is a depth edge all round.
  const StereoFrame frame = floorAndSphereFrame(0, 1.0);
  MapperConfig off;
  off.edge_reject_radius_px = 0;
  MapperConfig on;  // the default: radius 1, jump 1 px
  ASSERT_EQ(on.edge_reject_radius_px, 1);
  Mapper with_off(off), with_on(on);
  const IntegrationResult a = with_off.integrate(frame), b = with_on.integrate(frame);
  ASSERT_TRUE(a.accepted && b.accepted);
  EXPECT_EQ(a.rejected.edge_pixels, 0u);
  EXPECT_GT(b.rejected.edge_pixels, 50u);  // the silhouette, hundreds of pixels long
  EXPECT_LT(b.rejected.edge_pixels, a.lookup.valid_points / 20);
  EXPECT_EQ(a.lookup.valid_points - b.lookup.valid_points, b.rejected.edge_pixels);
  EXPECT_EQ(b.rejected.speckle_pixels, 0u);  // off by default
}
