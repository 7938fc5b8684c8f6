// WGS84 geodetic <-> ECEF <-> ENU: published reference points and round trips.
#include "hameritt/cop/geodetic.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace hameritt::cop {
namespace {

struct Reference {
  Geodetic lla;
  Eigen::Vector3d ecef;
  double tolerance;  // metres: the reference's published precision
};

// Published conversions: the ellipsoid's axes (NIMA TR8350.2: a = 6378137 m, b = 6356752.3142 m)
// and city points tabulated to 0.1 m (Vancouver, Toronto, Beijing) and Everest's summit to 1 mm.
const Reference kReferences[] = {
    {{0, 0, 0}, {6378137.0, 0, 0}, 1e-6},
    {{0, 90, 0}, {0, 6378137.0, 0}, 1e-6},
    {{90, 0, 0}, {0, 0, 6356752.3142}, 1e-4},
    {{-90, 0, 0}, {0, 0, -6356752.3142}, 1e-4},
    {{49.2827, -123.1207, 0.0}, {-2277772.9, -3491338.7, 4811126.5}, 0.06},
    {{43.7615, -79.41107, 0.0}, {847846.8, -4535275.1, 4388991.1}, 0.06},
    {{39.9138, 116.3636, 0.0}, {-2175414.8, 4389344.3, 4070649.0}, 0.06},
    {{27.9861, 86.9226, 8848}, {303011.566, 5636116.783, 2979297.096}, 1e-3},
};

TEST(Geodetic, MatchesPublishedReferencePoints) {
  for (const Reference& r : kReferences) {
    const Eigen::Vector3d e = geodeticToEcef(r.lla);
    EXPECT_LT((e - r.ecef).cwiseAbs().maxCoeff(), r.tolerance)
        << r.lla.latitude << " " << r.lla.longitude << ": " << e.transpose();
    const Geodetic back = ecefToGeodetic(r.ecef);
    // 1e-8 degrees is ~1 mm on the ground.
    EXPECT_NEAR(back.latitude, r.lla.latitude, r.tolerance * 1e-5 + 1e-9);
    if (std::abs(r.lla.latitude) < 90) {
      EXPECT_NEAR(back.longitude, r.lla.longitude, r.tolerance * 1e-5 + 1e-9);
    }
    EXPECT_NEAR(back.altitude, r.lla.altitude, r.tolerance + 1e-6);
  }
}

TEST(Geodetic, RoundTripsEverywhereToWellUnderAMillimetre) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> lat(-90, 90), lon(-180, 180), alt(-500, 20000);
  for (int i = 0; i < 20000; ++i) {
    const Geodetic g{lat(rng), lon(rng), alt(rng)};
    const Eigen::Vector3d e = geodeticToEcef(g);
    const Geodetic back = ecefToGeodetic(e);
    EXPECT_LT((geodeticToEcef(back) - e).norm(), 1e-6) << g.latitude << " " << g.longitude;
    EXPECT_NEAR(back.altitude, g.altitude, 1e-6);
  }
}

TEST(Geodetic, EnuAxesAtTheMissionOrigin) {
  const Geodetic origin{42.4851, -71.1873, 40.0};  // scenarios/default
  const EnuFrame f(origin);
  EXPECT_LT(f.toEnu(origin).norm(), 1e-6);
  // Straight up is +z.
  const Eigen::Vector3d up = f.toEnu({origin.latitude, origin.longitude, origin.altitude + 100});
  EXPECT_LT((up - Eigen::Vector3d(0, 0, 100)).norm(), 1e-6);
  // North along the meridian: +y, the meridian arc of 0.001 deg at 42.4851 N is 111.083 m
  // (M = a(1-e2)/(1-e2 sin^2)^1.5), and a slight drop below the tangent plane.
  const Eigen::Vector3d north =
      f.toEnu({origin.latitude + 0.001, origin.longitude, origin.altitude});
  EXPECT_NEAR(north.x(), 0.0, 1e-6);
  EXPECT_NEAR(north.y(), 111.083, 0.01);
  EXPECT_LT(north.z(), 0.0);
  // East along the parallel: +x, N cos(lat) * 0.001 deg = 82.219 m.
  const Eigen::Vector3d east =
      f.toEnu({origin.latitude, origin.longitude + 0.001, origin.altitude});
  EXPECT_NEAR(east.x(), 82.219, 0.01);
  EXPECT_NEAR(east.y(), 0.0, 0.01);
}

TEST(Geodetic, EnuRoundTripsKnownMapPoints) {
  const EnuFrame f({42.4851, -71.1873, 40.0});
  const Eigen::Vector3d points[] = {{0, 0, 0},          {-388.287, 108.702, 0}, {5.184, 1.75, 0},
                                    {500, -500, 120.5}, {-10000, 10000, 3000},  {1e5, 2e5, -50}};
  for (const Eigen::Vector3d& p : points) {
    const Geodetic g = f.toGeodetic(p);
    EXPECT_LT((f.toEnu(g) - p).norm(), 1e-6) << p.transpose();
  }
}

TEST(Geodetic, RejectsBadOrigins) {
  EXPECT_THROW(EnuFrame({91, 0, 0}), GeodeticError);
  EXPECT_THROW(EnuFrame({0, 181, 0}), GeodeticError);
  EXPECT_THROW(EnuFrame({NAN, 0, 0}), GeodeticError);
  EXPECT_THROW(geodeticToEcef({0, 0, INFINITY}), GeodeticError);
  try {
    validateOrigin({0, 200, 0}, "tak.yaml origin");
    FAIL();
  } catch (const GeodeticError& e) {
    EXPECT_NE(std::string(e.what()).find("tak.yaml origin: longitude"), std::string::npos);
  }
}

}  // namespace
}  // namespace hameritt::cop
