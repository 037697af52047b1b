// unitQuaternion(): a trajectory pose's rotation is taken only when it is one.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "stereo_fusion/trajectory/UnitQuaternion.h"

using namespace stereo_fusion;

TEST(UnitQuaternion, AZeroNonFiniteOrFarFromUnitQuaternionIsRefused) {
  std::string why;
  EXPECT_FALSE(unitQuaternion(0, 0, 0, 0, &why));
  EXPECT_NE(why.find("norm 0"), std::string::npos) << why;
  EXPECT_FALSE(unitQuaternion(0, 0, 0, 2, &why));  // |q| = 2: a scaled matrix, no rotation
  EXPECT_NE(why.find("norm 2"), std::string::npos) << why;
  EXPECT_FALSE(unitQuaternion(std::numeric_limits<double>::quiet_NaN(), 0, 0, 1, &why));
  EXPECT_NE(why.find("not finite"), std::string::npos) << why;
  EXPECT_FALSE(unitQuaternion(0, 0, 0, std::numeric_limits<double>::infinity(), &why));
  EXPECT_FALSE(unitQuaternion(0, 0, 0, 1.0 + 1.01 * kMaxQuaternionNormError, &why));
}

TEST(UnitQuaternion, ASlightlyOffQuaternionIsNormalised) {
  std::string why;
  // 90° about z, written with 4 decimals: |q| = 0.99999...; and the same scaled by 1.005.
  const auto q = unitQuaternion(0, 0, 0.7071, 0.7071, &why);
  ASSERT_TRUE(q) << why;
  EXPECT_NEAR(q->norm(), 1.0, 1e-15);
  EXPECT_NEAR(q->toRotationMatrix()(0, 1), -1.0, 1e-12);
  const auto scaled = unitQuaternion(0, 0, 1.005 * std::sqrt(0.5), 1.005 * std::sqrt(0.5), &why);
  ASSERT_TRUE(scaled) << why;
  EXPECT_TRUE(scaled->isApprox(*q, 1e-4));
  const auto identity = unitQuaternion(0, 0, 0, 1, &why);
  ASSERT_TRUE(identity);
  EXPECT_TRUE(identity->toRotationMatrix().isIdentity(0));
}
