#pragma once
// WGS84 geodetic coordinates, Earth-centred Earth-fixed (ECEF) and a local East-North-Up frame
// at a geodetic origin (NIMA TR8350.2, "Department of Defense World Geodetic System 1984",
// 3rd ed., 2000: a = 6378137 m, 1/f = 298.257223563). The scenario's map frame is such an ENU
// frame at the mission's origin (mission.json "frame.origin"; altitude = height above the
// ellipsoid, HAE).

#include <Eigen/Core>
#include <stdexcept>
#include <string>

namespace hameritt::cop {

// WGS84 defining constants and the derived ones the conversions use.
inline constexpr double kWgs84A = 6378137.0;
inline constexpr double kWgs84F = 1.0 / 298.257223563;
inline constexpr double kWgs84B = kWgs84A * (1.0 - kWgs84F);
inline constexpr double kWgs84E2 = kWgs84F * (2.0 - kWgs84F);

// Bad geodetic input (latitude outside [-90, 90], a non-finite value).
class GeodeticError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// A point on or above the WGS84 ellipsoid: degrees, degrees, metres above the ellipsoid.
struct Geodetic {
  double latitude = 0.0;
  double longitude = 0.0;
  double altitude = 0.0;
};

// Geodetic -> ECEF (metres). Throws GeodeticError for a latitude outside [-90, 90] or NaN.
Eigen::Vector3d geodeticToEcef(const Geodetic& g);

// ECEF -> geodetic by Newton iteration on the latitude to machine precision (a round trip with
// geodeticToEcef agrees to well under a millimetre anywhere from the Earth's centre region out).
// Longitude in (-180, 180].
Geodetic ecefToGeodetic(const Eigen::Vector3d& ecef);

// The local East-North-Up frame tangent to the ellipsoid at an origin: the map frame.
class EnuFrame {
 public:
  // Throws GeodeticError for a bad origin.
  explicit EnuFrame(const Geodetic& origin);

  // Geodetic -> ENU metres.
  Eigen::Vector3d toEnu(const Geodetic& g) const;
  // ENU metres -> geodetic.
  Geodetic toGeodetic(const Eigen::Vector3d& enu) const;

  const Geodetic& origin() const { return origin_; }

 private:
  Geodetic origin_;
  Eigen::Vector3d origin_ecef_;
  Eigen::Matrix3d ecef_to_enu_;  // rows: east, north, up unit vectors in ECEF
};

// Checks an origin: finite values, latitude in [-90, 90], longitude in [-180, 180]; the error
// names `what` (e.g. "tak.yaml origin").
void validateOrigin(const Geodetic& g, const std::string& what);

}  // namespace hameritt::cop
