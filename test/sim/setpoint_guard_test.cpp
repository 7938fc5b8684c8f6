#include "hameritt/sim/setpoint_guard.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hameritt/scenario/error.h"

namespace hameritt::sim {
namespace {

const double kNan = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

SetpointGuard guard() {
  Geofence f;
  f.min = Vec3(-100, -50, 0);
  f.max = Vec3(100, 50, 80);
  f.brake_distance = 20;
  return SetpointGuard(f, QuadrotorParams());
}

TEST(SetpointGuard, RejectsNonFiniteVelocityNamingTheField) {
  const SetpointGuard g = guard();
  for (int axis = 0; axis < 3; ++axis) {
    for (double bad : {kNan, kInf, -kInf}) {
      Vec3 v(1, 2, 0.5);
      v[axis] = bad;
      double w = 0;
      const SetpointCheck c = g.checkVelocity(&v, &w);
      EXPECT_NE(c.error.find(std::string("linear.") + "xyz"[axis]), std::string::npos) << c.error;
    }
  }
  Vec3 v(1, 0, 0);
  double w = kNan;
  EXPECT_NE(g.checkVelocity(&v, &w).error.find("angular.z"), std::string::npos);
}

TEST(SetpointGuard, ClampsAbsurdVelocityToTheControllerLimits) {
  const SetpointGuard g = guard();
  const QuadrotorParams p;
  Vec3 v(3e8, 4e8, 1e9);
  double w = -1e6;
  const SetpointCheck c = g.checkVelocity(&v, &w);
  EXPECT_TRUE(c.error.empty());
  EXPECT_FALSE(c.clamped.empty());
  EXPECT_NEAR(std::hypot(v.x(), v.y()), p.max_horizontal_speed, 1e-9);
  EXPECT_NEAR(v.x() / v.y(), 0.75, 1e-12);  // direction kept
  EXPECT_EQ(v.z(), p.max_climb);
  EXPECT_EQ(w, -p.max_yaw_rate);
  Vec3 ok(1, -2, -1);
  double w0 = 0.1;
  const SetpointCheck fine = g.checkVelocity(&ok, &w0);
  EXPECT_TRUE(fine.error.empty());
  EXPECT_TRUE(fine.clamped.empty());
  EXPECT_EQ(ok, Vec3(1, -2, -1));
}

TEST(SetpointGuard, ClampsPositionsIntoTheFenceAndRejectsNonFinite) {
  const SetpointGuard g = guard();
  Vec3 p(1e12, -1e12, -5);
  double yaw = kInf;
  const SetpointCheck c = g.checkPosition(&p, &yaw);
  EXPECT_TRUE(c.error.empty());
  EXPECT_EQ(p, Vec3(80, -30, 0));  // brake_distance inside the sides, the floor is the ground
  EXPECT_EQ(yaw, 0.0);
  EXPECT_NE(c.clamped.find("pose.position.x"), std::string::npos);
  Vec3 nan(0, kNan, 10);
  double y2 = 0;
  EXPECT_NE(g.checkPosition(&nan, &y2).error.find("pose.position.y"), std::string::npos);
  Vec3 inside(10, 10, 40);
  double y3 = 1;
  const SetpointCheck in = g.checkPosition(&inside, &y3);
  EXPECT_TRUE(in.clamped.empty());
  EXPECT_EQ(inside, Vec3(10, 10, 40));
}

TEST(SetpointGuard, FenceDropsOutwardVelocityNearAFaceAndReturnsBeyondIt) {
  const SetpointGuard g = guard();
  const Vec3 out(12, -12, 3);
  EXPECT_EQ(g.fenceVelocity(Vec3(0, 0, 30), out), out);               // far from every face
  EXPECT_EQ(g.fenceVelocity(Vec3(85, 0, 30), out), Vec3(0, -12, 3));  // near +x
  EXPECT_EQ(g.fenceVelocity(Vec3(0, -45, 70), out), Vec3(12, 0, 0));  // near -y and the ceiling
  EXPECT_EQ(g.fenceVelocity(Vec3(0, 0, 1), Vec3(0, 0, -2)), Vec3(0, 0, -2));    // landing allowed
  EXPECT_EQ(g.fenceVelocity(Vec3(101, 0, 30), out), Vec3(-1, -12, 3));          // beyond: return
  EXPECT_EQ(g.fenceVelocity(Vec3(85, 0, 30), Vec3(-5, 0, 0)), Vec3(-5, 0, 0));  // inward kept
}

TEST(SetpointGuard, RejectsAnEmptyOrNonFiniteFence) {
  Geofence f;
  f.max = Vec3(1, 1, 0);
  EXPECT_THROW(SetpointGuard(f, QuadrotorParams()), scenario::ConfigError);
  f.max = Vec3(1, 1, kInf);
  EXPECT_THROW(SetpointGuard(f, QuadrotorParams()), scenario::ConfigError);
}

}  // namespace
}  // namespace hameritt::sim
