#include "hameritt/geometry/segment.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hameritt::geometry {

namespace {

double maxAbs(const Vec2& v) { return std::max(std::fabs(v.x()), std::fabs(v.y())); }

// Absolute tolerance for touching tests: kEpsilon scaled by the magnitude of the coordinates
// involved (1e-9 near the origin, 1e-6 a kilometre out).
double touchTolerance(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  return kEpsilon * std::max({1.0, maxAbs(a), maxAbs(b), maxAbs(c), maxAbs(d)});
}

// Twice the signed area of the triangle (o, a, b): > 0 when b lies left of o->a.
double orient(const Vec2& o, const Vec2& a, const Vec2& b) { return cross2(a - o, b - o); }

bool strictlyOpposite(double u, double v) { return (u > 0.0 && v < 0.0) || (u < 0.0 && v > 0.0); }

}  // namespace

Vec2 closestPointOnSegment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 == 0.0) return a;
  const double t = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
  return a + t * ab;
}

double pointSegmentDistance(const Vec2& p, const Vec2& a, const Vec2& b) {
  return (p - closestPointOnSegment(p, a, b)).norm();
}

// Endpoint-on-segment cases (touching, collinear overlap, zero-length segments) are decided with
// a distance tolerance; everything else needs a proper crossing, decided by strict orientation
// signs. The result therefore agrees with segmentSegmentDistance() <= tolerance.
bool segmentsIntersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const double tol = touchTolerance(a, b, c, d);
  if (pointSegmentDistance(a, c, d) <= tol || pointSegmentDistance(b, c, d) <= tol ||
      pointSegmentDistance(c, a, b) <= tol || pointSegmentDistance(d, a, b) <= tol) {
    return true;
  }
  return strictlyOpposite(orient(c, d, a), orient(c, d, b)) &&
         strictlyOpposite(orient(a, b, c), orient(a, b, d));
}

double segmentSegmentDistance(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  if (segmentsIntersect(a, b, c, d)) return 0.0;
  return std::min({pointSegmentDistance(a, c, d), pointSegmentDistance(b, c, d),
                   pointSegmentDistance(c, a, b), pointSegmentDistance(d, a, b)});
}

// The unique common point of the two closed segments: a crossing, a T-junction or two segments
// meeting end to end. Returns nothing when they are disjoint or share a stretch (collinear
// overlap). A zero-length segment lying on the other one yields its position.
std::optional<Vec2> segmentIntersectionPoint(const Vec2& a, const Vec2& b, const Vec2& c,
                                             const Vec2& d) {
  if (!segmentsIntersect(a, b, c, d)) return std::nullopt;
  const Vec2 r = b - a;
  const Vec2 s = d - c;
  const double rr = r.squaredNorm();
  const double ss = s.squaredNorm();
  if (rr == 0.0) return a;
  if (ss == 0.0) return c;
  const double denom = cross2(r, s);
  if (std::fabs(denom) > kEpsilon * std::sqrt(rr * ss)) {
    const double t = std::clamp(cross2(c - a, s) / denom, 0.0, 1.0);
    return Vec2(a + t * r);
  }
  // Parallel and touching, hence collinear: a single common point only if the parameter
  // intervals meet at one end.
  const double t0 = (c - a).dot(r) / rr;
  const double t1 = (d - a).dot(r) / rr;
  const double lo = std::max(0.0, std::min(t0, t1));
  const double hi = std::min(1.0, std::max(t0, t1));
  if ((hi - lo) * std::sqrt(rr) > touchTolerance(a, b, c, d)) return std::nullopt;
  return Vec2(a + 0.5 * (lo + hi) * r);
}

double polylineLength(const std::vector<Vec2>& pts) {
  double total = 0.0;
  for (std::size_t i = 1; i < pts.size(); ++i) total += (pts[i] - pts[i - 1]).norm();
  return total;
}

Vec2 polylinePointAt(const std::vector<Vec2>& pts, double s) {
  if (pts.empty()) throw GeometryError("polylinePointAt: empty polyline");
  if (!(s > 0.0)) return pts.front();  // also catches NaN
  double remaining = s;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const double len = (pts[i] - pts[i - 1]).norm();
    if (remaining <= len) {
      return len > 0.0 ? Vec2(pts[i - 1] + (remaining / len) * (pts[i] - pts[i - 1])) : pts[i];
    }
    remaining -= len;
  }
  return pts.back();
}

double pointPolylineDistance(const Vec2& p, const std::vector<Vec2>& pts) {
  if (pts.empty()) throw GeometryError("pointPolylineDistance: empty polyline");
  if (pts.size() == 1) return (p - pts.front()).norm();
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < pts.size(); ++i) {
    best = std::min(best, pointSegmentDistance(p, pts[i - 1], pts[i]));
  }
  return best;
}

}  // namespace hameritt::geometry
