#include "hameritt/cop/geodetic.h"

#include <Eigen/Dense>
#include <cmath>

namespace hameritt::cop {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

}  // namespace

void validateOrigin(const Geodetic& g, const std::string& what) {
  if (!std::isfinite(g.latitude) || g.latitude < -90.0 || g.latitude > 90.0)
    throw GeodeticError(what + ": latitude " + std::to_string(g.latitude) +
                        " (expected degrees in [-90, 90])");
  if (!std::isfinite(g.longitude) || g.longitude < -180.0 || g.longitude > 180.0)
    throw GeodeticError(what + ": longitude " + std::to_string(g.longitude) +
                        " (expected degrees in [-180, 180])");
  if (!std::isfinite(g.altitude))
    throw GeodeticError(what + ": altitude is not a finite number of metres");
}

Eigen::Vector3d geodeticToEcef(const Geodetic& g) {
  if (!std::isfinite(g.latitude) || std::abs(g.latitude) > 90.0 || !std::isfinite(g.longitude) ||
      !std::isfinite(g.altitude))
    throw GeodeticError("geodeticToEcef: bad point (" + std::to_string(g.latitude) + ", " +
                        std::to_string(g.longitude) + ", " + std::to_string(g.altitude) + ")");
  const double lat = g.latitude * kDegToRad, lon = g.longitude * kDegToRad;
  const double s = std::sin(lat), c = std::cos(lat);
  const double n = kWgs84A / std::sqrt(1.0 - kWgs84E2 * s * s);  // prime vertical radius
  return {(n + g.altitude) * c * std::cos(lon), (n + g.altitude) * c * std::sin(lon),
          (n * (1.0 - kWgs84E2) + g.altitude) * s};
}

Geodetic ecefToGeodetic(const Eigen::Vector3d& ecef) {
  const double x = ecef.x(), y = ecef.y(), z = ecef.z();
  const double p = std::hypot(x, y);
  Geodetic g;
  g.longitude = std::atan2(y, x) / kDegToRad;
  if (p < 1e-9) {  // on the polar axis
    g.latitude = z >= 0 ? 90.0 : -90.0;
    g.altitude = std::abs(z) - kWgs84B;
    return g;
  }
  // Fixed point on tan(lat) = (z + e2 N sin(lat)) / p, started from Bowring's parametric guess;
  // it contracts by ~e2 per step, so a handful of steps reach machine precision.
  double lat = std::atan2(z, p * (1.0 - kWgs84E2));
  for (int i = 0; i < 10; ++i) {
    const double s = std::sin(lat);
    const double n = kWgs84A / std::sqrt(1.0 - kWgs84E2 * s * s);
    const double next = std::atan2(z + kWgs84E2 * n * s, p);
    const bool done = std::abs(next - lat) < 1e-15;
    lat = next;
    if (done) break;
  }
  const double s = std::sin(lat), c = std::cos(lat);
  const double n = kWgs84A / std::sqrt(1.0 - kWgs84E2 * s * s);
  // Height from the better-conditioned component (p near the equator, z near the poles).
  g.altitude = std::abs(c) > 0.5 ? p / c - n : z / s - n * (1.0 - kWgs84E2);
  g.latitude = lat / kDegToRad;
  return g;
}

EnuFrame::EnuFrame(const Geodetic& origin) : origin_(origin) {
  validateOrigin(origin, "ENU origin");
  origin_ecef_ = geodeticToEcef(origin);
  const double lat = origin.latitude * kDegToRad, lon = origin.longitude * kDegToRad;
  const double sl = std::sin(lat), cl = std::cos(lat), so = std::sin(lon), co = std::cos(lon);
  ecef_to_enu_ << -so, co, 0.0,  //
      -sl * co, -sl * so, cl,    //
      cl * co, cl * so, sl;
}

Eigen::Vector3d EnuFrame::toEnu(const Geodetic& g) const {
  return ecef_to_enu_ * (geodeticToEcef(g) - origin_ecef_);
}

Geodetic EnuFrame::toGeodetic(const Eigen::Vector3d& enu) const {
  return ecefToGeodetic(origin_ecef_ + ecef_to_enu_.transpose() * enu);
}

}  // namespace hameritt::cop
