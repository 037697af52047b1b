#include <gtest/gtest.h>

#include "stereo_fusion/integration/FusionMath.h"

using namespace stereo_fusion;

TEST(FusionMath, SignedDistanceEq315InFront) {
  // Voxel on the optical axis at 2 m, surface at 2.5 m: ‖x‖(1 − z/z_c) = 2·(1 − 1.25) = −0.5
  EXPECT_NEAR(signedDistanceAlongRay(0, 0, 2.0f, 2.5f), -0.5f, 1e-6f);
}

TEST(FusionMath, SignedDistanceEq315BehindOffAxis) {
  // x_c = (0.3, 0.4, 1.2), ‖x_c‖ = 1.3; surface at 1.0: 1.3·(1 − 1/1.2) = 0.216667 (behind)
  EXPECT_NEAR(signedDistanceAlongRay(0.3f, 0.4f, 1.2f, 1.0f), 1.3f / 6.0f, 1e-6f);
  // Along the ray the surface point is x_c·z/z_c; the distance between them is the same value.
  const float s = 1.0f / 1.2f;
  const float along = std::sqrt(0.09f + 0.16f + 1.44f) * (1.0f - s);
  EXPECT_NEAR(signedDistanceAlongRay(0.3f, 0.4f, 1.2f, 1.0f), along, 1e-6f);
  EXPECT_NEAR(signedDistanceAlongRay(0.3f, 0.4f, 1.0f, 1.0f), 0.0f, 1e-7f);  // on the surface
}

TEST(FusionMath, SteinbrueckerWeightEq310HandWorked) {
  const float delta = 0.02f, phi = 0.08f;
  EXPECT_FLOAT_EQ(steinbrueckerWeight(-0.5f, delta, phi), 1.0f);  // free space in front
  EXPECT_FLOAT_EQ(steinbrueckerWeight(0.01f, delta, phi), 1.0f);
  EXPECT_FLOAT_EQ(steinbrueckerWeight(0.02f, delta, phi), 1.0f);  // (0.08−0.02)/0.06
  EXPECT_FLOAT_EQ(steinbrueckerWeight(0.05f, delta, phi), 0.5f);  // (0.08−0.05)/0.06
  EXPECT_FLOAT_EQ(steinbrueckerWeight(0.08f, delta, phi), 0.0f);
  EXPECT_FLOAT_EQ(steinbrueckerWeight(0.09f, delta, phi), 0.0f);  // beyond Φ: unobserved
}

TEST(FusionMath, WeightFallsOffOnlyBehindTheSurface) {
  // The unobserved side is behind (d > 0): in front the weight never drops.
  for (float d = -0.3f; d < 0.0f; d += 0.01f) EXPECT_EQ(steinbrueckerWeight(d, 0.02f, 0.08f), 1.0f);
  float previous = 1.0f;
  for (float d = 0.0f; d <= 0.08f; d += 0.005f) {
    const float w = steinbrueckerWeight(d, 0.02f, 0.08f);
    EXPECT_LE(w, previous);
    previous = w;
  }
}

TEST(FusionMath, ModesHandWorked) {
  // constant: 1 inside the band, 0 beyond Φ
  EXPECT_FLOAT_EQ(measurementWeight(WeightMode::kConstant, 0.05f, 0.02f, 0.08f, 2.0f, 1.0f), 1.0f);
  EXPECT_FLOAT_EQ(measurementWeight(WeightMode::kConstant, 0.09f, 0.02f, 0.08f, 2.0f, 1.0f), 0.0f);
  // depth aware at z = 2, z_ref = 1: 0.5 · (1/2)² = 0.125
  EXPECT_FLOAT_EQ(measurementWeight(WeightMode::kDepthAware, 0.05f, 0.02f, 0.08f, 2.0f, 1.0f),
                  0.125f);
  EXPECT_FLOAT_EQ(measurementWeight(WeightMode::kDepthAware, -0.05f, 0.02f, 0.08f, 0.5f, 1.0f),
                  4.0f);
}

TEST(FusionMath, RunningAverageEq38Eq39HandWorked) {
  Voxel v;
  v.sdf_m = 0.1f;
  v.weight = 3.0f;
  v.r = 100;
  v.g = 50;
  v.b = 0;
  const uint8_t rgb[3] = {200, 250, 10};
  fuseMeasurement(&v, -0.02f, 1.0f, 100.0f, rgb);
  EXPECT_NEAR(v.sdf_m, (3 * 0.1f + 1 * -0.02f) / 4, 1e-7f);  // 0.07
  EXPECT_FLOAT_EQ(v.weight, 4.0f);
  EXPECT_EQ(v.r, 125);  // (3·100 + 200)/4
  EXPECT_EQ(v.g, 100);  // (3·50 + 250)/4
  EXPECT_EQ(v.b, 3);    // (0 + 10)/4 = 2.5, rounded half up
}

TEST(FusionMath, AContradictedVoxelKeepsPartOfItsWeightHandWorked) {
  // Stored 0.05 behind a surface; the measurement says 0.04 in front; Φ = 0.08.
  // |0.05 − (−0.04)| = 0.09 > 0.08: W = 10 · 0.8 = 8, then (8·0.05 + 1·(−0.04)) / 9 = 0.04.
  Voxel v;
  v.sdf_m = 0.05f;
  v.weight = 10.0f;
  v.weight = weightBeforeUpdate(v.sdf_m, v.weight, -0.04f, 0.08f, 0.8f);
  EXPECT_FLOAT_EQ(v.weight, 8.0f);
  fuseMeasurement(&v, -0.04f, 1.0f, 100.0f, nullptr);
  EXPECT_NEAR(v.sdf_m, 0.04f, 1e-7f);
  EXPECT_FLOAT_EQ(v.weight, 9.0f);
  // |0.03 − (−0.04)| = 0.07 ≤ 0.08: agreement within the band keeps W (noise is averaged).
  EXPECT_FLOAT_EQ(weightBeforeUpdate(0.03f, 10.0f, -0.04f, 0.08f, 0.8f), 10.0f);
  // Exactly Φ apart is no contradiction; keep = 1 is the thesis' plain average.
  EXPECT_FLOAT_EQ(weightBeforeUpdate(0.04f, 10.0f, -0.04f, 0.08f, 0.8f), 10.0f);
  EXPECT_FLOAT_EQ(weightBeforeUpdate(0.05f, 10.0f, -0.04f, 0.08f, 1.0f), 10.0f);
}

TEST(FusionMath, FirstMeasurementIsTakenAsIs) {
  Voxel v;
  fuseMeasurement(&v, 0.033f, 0.4f, 100.0f, nullptr);
  EXPECT_FLOAT_EQ(v.sdf_m, 0.033f);
  EXPECT_FLOAT_EQ(v.weight, 0.4f);
}

TEST(FusionMath, WeightCap) {
  Voxel v;
  v.sdf_m = 0.1f;
  v.weight = 3.0f;
  fuseMeasurement(&v, -0.02f, 1.0f, 3.5f, nullptr);
  EXPECT_NEAR(v.sdf_m, 0.07f, 1e-7f);  // the average uses the true weights ...
  EXPECT_FLOAT_EQ(v.weight, 3.5f);     // ... then W is capped
  // At the cap, new measurements keep moving the value: the map can still change.
  for (int i = 0; i < 50; ++i) fuseMeasurement(&v, -0.05f, 1.0f, 3.5f, nullptr);
  EXPECT_NEAR(v.sdf_m, -0.05f, 1e-4f);
}
