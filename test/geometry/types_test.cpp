#include "hameritt/geometry/types.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <utility>
#include <vector>

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

// minSqrt(cap, x) is std::min(cap, std::sqrt(x)) bit for bit, also for x just above and below
// cap * cap, for zero and tiny caps, and for infinite and NaN arguments.
TEST(TypesTest, MinSqrtEqualsMinOfTheRoot) {
  std::mt19937_64 gen(7);
  std::uniform_real_distribution<double> speed(0.0, 40.0), rel(-1e-6, 1e-6);
  std::vector<std::pair<double, double>> cases = {{0.0, 0.0},
                                                  {0.0, 5.0},
                                                  {3.0, 9.0},
                                                  {3.0, std::nextafter(9.0, 10.0)},
                                                  {3.0, std::nextafter(9.0, 0.0)},
                                                  {1e-160, 1e-320},
                                                  {1e-200, 4.9e-324},
                                                  {2.0, std::numeric_limits<double>::infinity()},
                                                  {std::numeric_limits<double>::infinity(), 4.0},
                                                  {2.0, std::nan("")},
                                                  {std::nan(""), 4.0},
                                                  {-1.0, 4.0}};
  for (int i = 0; i < 200000; ++i) {
    const double cap = speed(gen);
    double x = cap * cap * (1.0 + rel(gen));
    if (i % 4 == 0) x = std::nextafter(cap * cap * (1.0 + 1e-9), i % 8 == 0 ? 0.0 : 1e300);
    if (i % 4 == 1) x = speed(gen) * speed(gen);
    cases.emplace_back(cap, x);
  }
  int checked = 0;
  for (const auto& [cap, x] : cases) {
    const double expected = std::min(cap, std::sqrt(x));
    const double got = hameritt::geometry::minSqrt(cap, x);
    if (std::isnan(expected)) {
      EXPECT_TRUE(std::isnan(got)) << cap << " " << x;
    } else {
      ASSERT_EQ(std::memcmp(&got, &expected, sizeof(got)), 0) << cap << " " << x;
    }
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(cases.size()));
}
