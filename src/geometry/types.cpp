#include "hameritt/geometry/types.h"

#include <cmath>

namespace hameritt::geometry {

namespace {
constexpr double kTwoPi = 2.0 * kPi;
}  // namespace

// std::remainder is exact and lands in [-pi, pi]; only -pi needs moving to +pi.
double wrapPi(double a) {
  // Inside (-pi, pi] the remainder is `a` itself (it is exact): skip the library call.
  if (a > -kPi && a <= kPi) return a;
  double r = std::remainder(a, kTwoPi);
  if (r <= -kPi) r += kTwoPi;
  return r;
}

double wrapTwoPi(double a) {
  double r = std::fmod(a, kTwoPi);
  if (r < 0.0) r += kTwoPi;
  // A tiny negative input rounds up to exactly 2*pi above; keep the interval half-open.
  if (r >= kTwoPi) r = 0.0;
  return r;
}

double wrapDeg360(double deg) {
  double r = std::fmod(deg, 360.0);
  if (r < 0.0) r += 360.0;
  if (r >= 360.0) r = 0.0;
  return r;
}

double angleDiffDeg(double a_deg, double b_deg) {
  return std::fabs(std::remainder(a_deg - b_deg, 360.0));
}

}  // namespace hameritt::geometry
