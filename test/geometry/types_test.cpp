#include "hameritt/geometry/types.h"

#include <gtest/gtest.h>

namespace hameritt::geometry {
namespace {

TEST(TypesTest, WrapPiLandsInHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(wrapPi(0.0), 0.0);
  EXPECT_DOUBLE_EQ(wrapPi(kPi), kPi);
  EXPECT_DOUBLE_EQ(wrapPi(-kPi), kPi);  // -pi is outside (-pi, pi]
  EXPECT_NEAR(wrapPi(1.5 * kPi), -0.5 * kPi, 1e-12);
  EXPECT_NEAR(wrapPi(-1.5 * kPi), 0.5 * kPi, 1e-12);
  EXPECT_NEAR(wrapPi(2.5 * kPi), 0.5 * kPi, 1e-12);
  EXPECT_NEAR(wrapPi(-2.5 * kPi), -0.5 * kPi, 1e-12);
  EXPECT_NEAR(wrapPi(2.0 * kPi), 0.0, 1e-12);
}

TEST(TypesTest, WrapTwoPiLandsInHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(wrapTwoPi(0.0), 0.0);
  EXPECT_NEAR(wrapTwoPi(-0.5 * kPi), 1.5 * kPi, 1e-12);
  EXPECT_DOUBLE_EQ(wrapTwoPi(2.0 * kPi), 0.0);
  EXPECT_NEAR(wrapTwoPi(5.0 * kPi), kPi, 1e-12);
  const double tiny = wrapTwoPi(-1e-20);
  EXPECT_GE(tiny, 0.0);
  EXPECT_LT(tiny, 2.0 * kPi);
}

TEST(TypesTest, WrapDeg360) {
  EXPECT_DOUBLE_EQ(wrapDeg360(-90.0), 270.0);
  EXPECT_DOUBLE_EQ(wrapDeg360(360.0), 0.0);
  EXPECT_DOUBLE_EQ(wrapDeg360(725.0), 5.0);
  EXPECT_DOUBLE_EQ(wrapDeg360(-720.0), 0.0);
  const double tiny = wrapDeg360(-1e-14);
  EXPECT_GE(tiny, 0.0);
  EXPECT_LT(tiny, 360.0);
}

TEST(TypesTest, AngleDiffDeg) {
  EXPECT_DOUBLE_EQ(angleDiffDeg(350.0, 10.0), 20.0);
  EXPECT_DOUBLE_EQ(angleDiffDeg(10.0, 350.0), 20.0);
  EXPECT_DOUBLE_EQ(angleDiffDeg(0.0, 180.0), 180.0);
  EXPECT_DOUBLE_EQ(angleDiffDeg(-170.0, 170.0), 20.0);
  EXPECT_DOUBLE_EQ(angleDiffDeg(720.0, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(angleDiffDeg(90.0, -90.0), 180.0);
}

TEST(TypesTest, DegreeConversionAndCross) {
  EXPECT_DOUBLE_EQ(degToRad(180.0), kPi);
  EXPECT_DOUBLE_EQ(radToDeg(0.5 * kPi), 90.0);
  EXPECT_DOUBLE_EQ(cross2(Vec2(1, 0), Vec2(0, 1)), 1.0);
  EXPECT_DOUBLE_EQ(cross2(Vec2(0, 1), Vec2(1, 0)), -1.0);
  EXPECT_DOUBLE_EQ(cross2(Vec2(2, 3), Vec2(4, 6)), 0.0);
}

}  // namespace
}  // namespace hameritt::geometry
