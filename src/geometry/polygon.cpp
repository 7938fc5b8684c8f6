#include "hameritt/geometry/polygon.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace hameritt::geometry {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double maxAbs(const Vec2& v) { return std::max(std::fabs(v.x()), std::fabs(v.y())); }

double maxAbs(const std::vector<Vec2>& pts) {
  double m = 0.0;
  for (const Vec2& v : pts) m = std::max(m, maxAbs(v));
  return m;
}

// Absolute tolerance for on-boundary tests, relative to the size of the coordinates.
double tolerance(double max_abs_coordinate) { return kEpsilon * std::max(1.0, max_abs_coordinate); }

const Vec2& next(const std::vector<Vec2>& v, std::size_t i) {
  return v[i + 1 == v.size() ? 0 : i + 1];
}

}  // namespace

Polygon::Polygon(std::vector<Vec2> vertices) : vertices_(std::move(vertices)) {}

double Polygon::signedArea() const {
  if (vertices_.size() < 3) return 0.0;
  // Shoelace relative to the first vertex, which keeps precision far from the origin.
  const Vec2& o = vertices_.front();
  double twice = 0.0;
  for (std::size_t i = 1; i + 1 < vertices_.size(); ++i) {
    twice += cross2(vertices_[i] - o, vertices_[i + 1] - o);
  }
  return 0.5 * twice;
}

double Polygon::area() const { return std::fabs(signedArea()); }

Vec2 Polygon::centroid() const {
  if (vertices_.empty()) return Vec2(0.0, 0.0);
  Vec2 mean(0.0, 0.0);
  for (const Vec2& v : vertices_) mean += v;
  mean /= static_cast<double>(vertices_.size());

  const Aabb2 b = bounds();
  const double extent = (b.max - b.min).norm();
  const double a = signedArea();
  if (vertices_.size() < 3 || std::fabs(a) <= kEpsilon * extent * extent) return mean;

  const Vec2& o = vertices_.front();
  Vec2 acc(0.0, 0.0);
  for (std::size_t i = 1; i + 1 < vertices_.size(); ++i) {
    const Vec2 p = vertices_[i] - o;
    const Vec2 q = vertices_[i + 1] - o;
    acc += cross2(p, q) * (p + q);
  }
  return o + acc / (6.0 * a);
}

Aabb2 Polygon::bounds() const {
  if (vertices_.empty()) return Aabb2{};
  Aabb2 b{vertices_.front(), vertices_.front()};
  for (const Vec2& v : vertices_) {
    b.min = b.min.cwiseMin(v);
    b.max = b.max.cwiseMax(v);
  }
  return b;
}

double Polygon::perimeter() const {
  if (vertices_.size() < 2) return 0.0;
  double total = 0.0;
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    total += (next(vertices_, i) - vertices_[i]).norm();
  }
  return total;
}

// Boundary first (within tolerance), then the non-zero winding rule with half-open edge
// crossings, so vertices and horizontal edges need no special cases. For a simple polygon the
// winding rule equals even-odd; for a self-overlapping ring (a hairpin band from
// bufferPolyline) it keeps the overlap inside.
bool Polygon::contains(const Vec2& p) const {
  if (vertices_.empty()) return false;
  const double tol = tolerance(std::max(maxAbs(vertices_), maxAbs(p)));
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    if (pointSegmentDistance(p, vertices_[i], next(vertices_, i)) <= tol) return true;
  }
  int winding = 0;
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    const Vec2& a = vertices_[i];
    const Vec2& b = next(vertices_, i);
    const double side = cross2(b - a, p - a);
    if (a.y() <= p.y()) {
      if (b.y() > p.y() && side > 0.0) ++winding;
    } else if (b.y() <= p.y() && side < 0.0) {
      --winding;
    }
  }
  return winding != 0;
}

double Polygon::boundaryDistance(const Vec2& p) const {
  double best = kInf;
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    best = std::min(best, pointSegmentDistance(p, vertices_[i], next(vertices_, i)));
  }
  return best;
}

double Polygon::distance(const Vec2& p) const {
  if (contains(p)) return 0.0;
  return boundaryDistance(p);
}

// Either an end lies in the region, or the segment meets the boundary; a segment with both
// ends outside cannot reach the interior without crossing an edge.
bool Polygon::intersectsSegment(const Vec2& a, const Vec2& b) const {
  if (vertices_.empty()) return false;
  if (contains(a) || contains(b)) return true;
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    if (segmentsIntersect(a, b, vertices_[i], next(vertices_, i))) return true;
  }
  return false;
}

bool Polygon::intersectsPolyline(const std::vector<Vec2>& pts) const {
  if (pts.empty()) return false;
  if (pts.size() == 1) return contains(pts.front());
  for (std::size_t i = 1; i < pts.size(); ++i) {
    if (intersectsSegment(pts[i - 1], pts[i])) return true;
  }
  return false;
}

bool Polygon::intersects(const Polygon& other) const {
  if (vertices_.empty() || other.vertices_.empty()) return false;
  const Aabb2 ba = bounds();
  const Aabb2 bb = other.bounds();
  const double tol =
      tolerance(std::max({maxAbs(ba.min), maxAbs(ba.max), maxAbs(bb.min), maxAbs(bb.max)}));
  const Vec2 slack(tol, tol);
  if (!Aabb2{ba.min - slack, ba.max + slack}.overlaps(bb)) return false;
  const auto& u = vertices_;
  const auto& v = other.vertices_;
  for (std::size_t i = 0; i < u.size(); ++i) {
    for (std::size_t j = 0; j < v.size(); ++j) {
      if (segmentsIntersect(u[i], next(u, i), v[j], next(v, j))) return true;
    }
  }
  // No boundary contact: either one region holds the other entirely, or they are disjoint.
  return contains(v.front()) || other.contains(u.front());
}

double Polygon::distance(const Polygon& other) const {
  if (vertices_.empty() || other.vertices_.empty()) return kInf;
  if (intersects(other)) return 0.0;
  const auto& u = vertices_;
  const auto& v = other.vertices_;
  double best = kInf;
  for (std::size_t i = 0; i < u.size(); ++i) {
    for (std::size_t j = 0; j < v.size(); ++j) {
      best = std::min(best, segmentSegmentDistance(u[i], next(u, i), v[j], next(v, j)));
    }
  }
  return best;
}

// An explicitly closed ring (last vertex equal to the first) is not simple: the closing edge
// has zero length, i.e. a vertex repeats. Collinear consecutive vertices are allowed; an edge
// folding back over its neighbour (a spike) is not.
bool Polygon::isSimple() const {
  const std::size_t n = vertices_.size();
  if (n < 3) return false;
  for (const Vec2& v : vertices_) {
    if (!v.allFinite()) return false;
  }
  const double tol = tolerance(maxAbs(vertices_));
  for (std::size_t i = 0; i < n; ++i) {
    if ((next(vertices_, i) - vertices_[i]).norm() <= tol) return false;
  }
  const Aabb2 b = bounds();
  if (area() <= tol * (b.max - b.min).norm()) return false;

  // Adjacent edges meet only at their shared vertex unless one folds back onto the other,
  // in which case the far end of the shorter one lies on the longer one.
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& prev = vertices_[(i + n - 1) % n];
    const Vec2& cur = vertices_[i];
    const Vec2& nxt = next(vertices_, i);
    if (pointSegmentDistance(nxt, prev, cur) <= tol ||
        pointSegmentDistance(prev, cur, nxt) <= tol) {
      return false;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // adjacent through the closing edge
      if (segmentsIntersect(vertices_[i], next(vertices_, i), vertices_[j], next(vertices_, j))) {
        return false;
      }
    }
  }
  return true;
}

// Reverses a clockwise ring while keeping the first vertex first.
Polygon Polygon::counterClockwise() const {
  if (signedArea() >= 0.0) return *this;
  std::vector<Vec2> out;
  out.reserve(vertices_.size());
  out.push_back(vertices_.front());
  for (std::size_t i = vertices_.size() - 1; i > 0; --i) out.push_back(vertices_[i]);
  return Polygon(std::move(out));
}

Polygon rectangle(const Vec2& min, const Vec2& max) {
  const Vec2 lo = min.cwiseMin(max);
  const Vec2 hi = min.cwiseMax(max);
  return Polygon({lo, Vec2(hi.x(), lo.y()), hi, Vec2(lo.x(), hi.y())});
}

Polygon orientedRectangle(const Vec2& c, double length, double width, double yaw) {
  const double hl = 0.5 * std::fabs(length);
  const double hw = 0.5 * std::fabs(width);
  const Vec2 u(std::cos(yaw), std::sin(yaw));  // along the heading
  const Vec2 v(-u.y(), u.x());                 // across, to the left
  return Polygon(
      {c - hl * u - hw * v, c + hl * u - hw * v, c + hl * u + hw * v, c - hl * u + hw * v});
}

// Builds the ring as the right-hand offset walked forward and the left-hand offset walked
// back. Outside a turn: a mitre point, or a bevel (two points) where the mitre would be longer
// than the full width (turns sharper than 120 degrees, U-turns). Inside a turn: the
// intersection of the two offset lines, when the kite it cuts off lies within both segments'
// rectangles; otherwise (short segments, U-turns) the ring runs through the vertex itself.
// Under the non-zero winding rule of contains() the region is then exactly the union of the
// segment rectangles and the outer joins, even when the ring overlaps itself.
Polygon bufferPolyline(const std::vector<Vec2>& polyline, double width) {
  if (!std::isfinite(width) || width <= 0.0) {
    throw GeometryError("bufferPolyline: width must be positive and finite");
  }
  for (const Vec2& p : polyline) {
    if (!p.allFinite()) throw GeometryError("bufferPolyline: non-finite point");
  }
  const double tol = tolerance(maxAbs(polyline));
  std::vector<Vec2> pts;
  pts.reserve(polyline.size());
  for (const Vec2& p : polyline) {
    if (pts.empty() || (p - pts.back()).norm() > tol) pts.push_back(p);
  }
  if (pts.size() < 2) throw GeometryError("bufferPolyline: fewer than 2 distinct points");

  const double h = 0.5 * width;
  const std::size_t segments = pts.size() - 1;
  std::vector<Vec2> dir(segments);
  std::vector<Vec2> left_normal(segments);
  std::vector<double> len(segments);
  for (std::size_t i = 0; i < segments; ++i) {
    const Vec2 d = pts[i + 1] - pts[i];
    len[i] = d.norm();
    dir[i] = d / len[i];
    left_normal[i] = Vec2(-dir[i].y(), dir[i].x());
  }

  std::vector<Vec2> right{pts.front() - h * left_normal.front()};
  std::vector<Vec2> left{pts.front() + h * left_normal.front()};
  for (std::size_t k = 1; k + 1 < pts.size(); ++k) {
    const Vec2& p = pts[k];
    const Vec2& na = left_normal[k - 1];
    const Vec2& nb = left_normal[k];
    const double c = dir[k - 1].dot(dir[k]);         // cosine of the turn angle
    const double s = cross2(dir[k - 1], dir[k]);     // sine, > 0 for a left turn
    const double outer_sign = s > 0.0 ? -1.0 : 1.0;  // right side is outside a left turn
    std::vector<Vec2>& outer = s > 0.0 ? right : left;
    std::vector<Vec2>& inner = s > 0.0 ? left : right;

    const Vec2 oa = outer_sign * na;
    const Vec2 ob = outer_sign * nb;
    if (c < -0.5) {
      outer.push_back(p + h * oa);
      outer.push_back(p + h * ob);
    } else {
      outer.push_back(p + h * (oa + ob) / (1.0 + c));
    }

    const Vec2 ia = -oa;
    const Vec2 ib = -ob;
    // The kite between the inner offsets' intersection and the vertex reaches h*sin(turn) or
    // h*tan(turn/2), whichever is larger, along each segment.
    const double reach = h * std::fabs(s) * std::max(1.0, 1.0 / (1.0 + c));
    const bool cut = 1.0 + c > 1e-12 && reach <= std::min(len[k - 1], len[k]);
    if (cut) {
      inner.push_back(p + h * (ia + ib) / (1.0 + c));
    } else {
      inner.push_back(p + h * ia);
      inner.push_back(p);
      inner.push_back(p + h * ib);
    }
  }
  right.push_back(pts.back() - h * left_normal.back());
  left.push_back(pts.back() + h * left_normal.back());

  std::vector<Vec2> ring;
  ring.reserve(right.size() + left.size());
  auto append = [&ring](const Vec2& v) {
    if (ring.empty() || ring.back() != v) ring.push_back(v);
  };
  for (const Vec2& v : right) append(v);
  for (auto it = left.rbegin(); it != left.rend(); ++it) append(*it);
  while (ring.size() > 1 && ring.back() == ring.front()) ring.pop_back();
  return Polygon(std::move(ring));
}

}  // namespace hameritt::geometry
