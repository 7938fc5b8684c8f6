// Test-only driver for test/scripts/test_geometry_oracle.py: answers many geometry cases at
// once with the project's own code, so that the script can compare each answer with Shapely.
//
// Input (stdin), one case per line, whitespace-separated numbers ("nan" = bound missing):
//   n x1 y1 ... xn yn   ax ay az bx by bz ta tb   qx qy   zmin zmax net nlt   m x1 y1 ... xm ym
// Output (stdout), one line per case, numbers with 17 significant digits:
//   area contains(q) distance(q) intersectsSegment(a,b) inside_length n_inside
//   intersects(other) distance(other) isSimple violation_duration
// inside_length: length of the 2-D segment a-b inside the polygon (adk::segmentInsidePolygon);
// violation_duration: total time of adk::violationIntervals() for the keep-out zone made of the
// polygon, the altitude band [zmin, zmax] and the window [net, nlt]. With m < 3 the two
// polygon-polygon answers are 0.
//
// Negative control: with HAMERITT_ORACLE_WRONG=boundary_outside the driver answers as a wrong
// library would that treats the ring as outside: a point within the library's own boundary
// tolerance of the ring is not contained, and a segment that only touches the ring (no length
// inside) does not intersect. The oracle must fail on these answers.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "hameritt/adk/constraint_monitor.h"
#include "hameritt/geometry/polygon.h"
#include "hameritt/geometry/segment.h"

namespace {

using hameritt::geometry::Polygon;
using hameritt::geometry::Vec2;
using hameritt::geometry::Vec3;

double next(std::istringstream& in) {
  std::string token;
  if (!(in >> token)) throw std::runtime_error("truncated case");
  return std::strtod(token.c_str(), nullptr);
}

std::vector<Vec2> ring(std::istringstream& in) {
  const int n = static_cast<int>(next(in));
  std::vector<Vec2> v;
  for (int i = 0; i < n; ++i) {
    const double x = next(in);
    v.emplace_back(x, next(in));
  }
  return v;
}

std::optional<double> bound(double v) {
  return std::isnan(v) ? std::nullopt : std::optional<double>(v);
}

// Distance from p to the ring of `v`.
double ringDistance(const std::vector<Vec2>& v, const Vec2& p) {
  double d = INFINITY;
  for (std::size_t i = 0; i < v.size(); ++i) {
    d = std::min(d, hameritt::geometry::pointSegmentDistance(p, v[i], v[(i + 1) % v.size()]));
  }
  return d;
}

}  // namespace

int main() {
  std::ios::sync_with_stdio(false);
  const char* wrong_env = std::getenv("HAMERITT_ORACLE_WRONG");
  const std::string wrong = wrong_env ? wrong_env : "";
  if (!wrong.empty() && wrong != "boundary_outside") {
    std::fprintf(stderr, "geometry_oracle: HAMERITT_ORACLE_WRONG: expected boundary_outside\n");
    return 2;
  }
  std::string line;
  std::size_t count = 0;
  while (std::getline(std::cin, line)) {
    if (line.empty()) continue;
    std::istringstream in(line);
    const Polygon poly(ring(in));
    double c[8];
    for (double& x : c) x = next(in);
    const Vec3 a(c[0], c[1], c[2]), b(c[3], c[4], c[5]);
    const double ta = c[6], tb = c[7];
    const double qx = next(in);
    const Vec2 q(qx, next(in));
    hameritt::scenario::KeepOutZone zone;
    zone.polygon = poly;
    zone.alt_min = bound(next(in));
    zone.alt_max = bound(next(in));
    zone.window.net = bound(next(in));
    zone.window.nlt = bound(next(in));
    const Polygon other(ring(in));

    const Vec2 a2 = a.head<2>(), b2 = b.head<2>();
    double inside = 0.0;
    const auto pieces = hameritt::adk::segmentInsidePolygon(poly, a2, b2);
    for (const auto& i : pieces) inside += i.length();
    inside *= (b2 - a2).norm();
    double violation = 0.0;
    for (const auto& i : hameritt::adk::violationIntervals(zone, a, b, ta, tb)) {
      violation += i.length();
    }
    const bool has_other = other.size() >= 3;
    bool contains = poly.contains(q);
    bool hits = poly.intersectsSegment(a2, b2);
    if (wrong == "boundary_outside") {
      double m = std::max(std::fabs(q.x()), std::fabs(q.y()));
      for (const Vec2& v : poly.vertices()) m = std::max({m, std::fabs(v.x()), std::fabs(v.y())});
      const double band = hameritt::geometry::kEpsilon * std::max(1.0, m);
      contains = contains && ringDistance(poly.vertices(), q) > band;
      hits = a2 == b2 ? poly.contains(a2) && ringDistance(poly.vertices(), a2) > band
                      : hits && inside > 0.0;
    }
    std::printf("%.17g %d %.17g %d %.17g %zu %d %.17g %d %.17g\n", poly.area(), contains ? 1 : 0,
                poly.distance(q), hits ? 1 : 0, inside, pieces.size(),
                has_other && poly.intersects(other) ? 1 : 0, has_other ? poly.distance(other) : 0.0,
                poly.isSimple() ? 1 : 0, violation);
    ++count;
  }
  std::fprintf(stderr, "geometry_oracle: %zu cases\n", count);
  return 0;
}
