#pragma once
// Basic geometric types and angle helpers. Frame: ENU metres (x east, y north, z up);
// angles in radians, counter-clockwise positive about +z; times in seconds from mission start.

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

namespace hameritt::geometry {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

constexpr double kPi = 3.14159265358979323846;
// Tolerance used by predicates that must treat touching/collinear cases consistently.
constexpr double kEpsilon = 1e-9;

// Thrown for geometrically invalid input (open polygon, negative size, NaN coordinate).
class GeometryError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Wraps an angle to (-pi, pi].
double wrapPi(double a);
// Wraps an angle to [0, 2*pi).
double wrapTwoPi(double a);
// Wraps an angle in degrees to [0, 360).
double wrapDeg360(double deg);
// Smallest absolute difference between two angles in degrees, in [0, 180].
double angleDiffDeg(double a_deg, double b_deg);

inline double degToRad(double d) { return d * kPi / 180.0; }
inline double radToDeg(double r) { return r * 180.0 / kPi; }

// std::min(cap, std::sqrt(x)), the same value, without the square root when x is clearly
// above cap * cap (relative margin 1e-9, far above the product's rounding error; cap large
// enough for cap * cap to be a normal number): the root, rounded, is then at least cap, so the
// minimum is cap. Speed profiles call it for every sample, most of which run at their cap.
inline double minSqrt(double cap, double x) {
  if (cap >= 1e-150 && x > cap * cap * (1.0 + 1e-9)) return cap;
  return std::min(cap, std::sqrt(x));
}

// 2D cross product (z of the 3D cross product).
inline double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

}  // namespace hameritt::geometry
