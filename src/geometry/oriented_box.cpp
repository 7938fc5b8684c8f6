#include "hameritt/geometry/oriented_box.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace hameritt::geometry {

namespace {

// Touching tolerance of a box, relative to the size of its coordinates. OccluderIndex pads its
// grid registration by twice this amount, so the two must stay in step.
double boxTolerance(const OrientedBox& b) {
  return kEpsilon * std::max({1.0, b.center.cwiseAbs().maxCoeff(), b.size.cwiseAbs().maxCoeff()});
}

// Cosine and sine of a yaw, remembered for the last two yaws seen on this thread: the same
// boxes are often asked many times in a row (a box's corners, then points and segments
// against it; pairs of boxes in footprintDistance). The values are those std::cos and
// std::sin return; yaws are compared by their bits, so -0 and +0 are kept apart.
struct YawTrig {
  std::uint64_t bits[2];
  double c[2], s[2];
  int next;  // the entry to replace on a miss (the one not used last)
};
// Starts with yaw +0 in both entries: cos(+0) = 1 and sin(+0) = +0 exactly.
__attribute__((tls_model("initial-exec"))) thread_local YawTrig t_last_yaw = {
    {0, 0}, {1.0, 1.0}, {0.0, 0.0}, 0};

inline void cosSin(double yaw, double* c, double* s) {
  std::uint64_t bits;
  std::memcpy(&bits, &yaw, sizeof(bits));
  YawTrig& last = t_last_yaw;
  int i;
  if (bits == last.bits[0]) {
    i = 0;
  } else if (bits == last.bits[1]) {
    i = 1;
  } else {
    i = last.next;
    last.c[i] = std::cos(yaw);
    last.s[i] = std::sin(yaw);
    last.bits[i] = bits;
  }
  last.next = 1 - i;  // the least recently used entry goes first
  *c = last.c[i];
  *s = last.s[i];
}

}  // namespace

std::array<Vec2, 4> OrientedBox::corners2() const {
  double cy, sy;
  cosSin(yaw, &cy, &sy);
  return corners2(cy, sy);
}

std::array<Vec2, 4> OrientedBox::corners2(double cy, double sy) const {
  const double hl = 0.5 * size.x();
  const double hw = 0.5 * size.y();
  const Vec2 u(cy, sy);         // body x in the world
  const Vec2 v(-u.y(), u.x());  // body y in the world
  const Vec2 c = center2();
  return {c - hl * u - hw * v, c + hl * u - hw * v, c + hl * u + hw * v, c - hl * u + hw * v};
}

Polygon OrientedBox::footprint() const {
  const auto c = corners2();
  return Polygon({c[0], c[1], c[2], c[3]});
}

Aabb2 OrientedBox::bounds2() const {
  const auto c = corners2();
  Aabb2 b{c[0], c[0]};
  for (const Vec2& p : c) {
    b.min = b.min.cwiseMin(p);
    b.max = b.max.cwiseMax(p);
  }
  return b;
}

Vec3 OrientedBox::toBody(const Vec3& p) const {
  const Vec3 d = p - center;
  double cy, sy;
  cosSin(yaw, &cy, &sy);
  return Vec3(cy * d.x() + sy * d.y(), -sy * d.x() + cy * d.y(), d.z());
}

bool OrientedBox::contains(const Vec3& p) const {
  double cy, sy;
  cosSin(yaw, &cy, &sy);
  return contains(p, cy, sy);
}

bool OrientedBox::contains(const Vec3& p, double cy, double sy) const {
  const Vec3 d = p - center;  // toBody() with the given cosine and sine
  const Vec3 q = Vec3(cy * d.x() + sy * d.y(), -sy * d.x() + cy * d.y(), d.z()).cwiseAbs();
  const Vec3 half = 0.5 * size.cwiseAbs() + Vec3::Constant(boxTolerance(*this));
  return q.x() <= half.x() && q.y() <= half.y() && q.z() <= half.z();
}

// Liang-Barsky clipping of the segment against the three slabs of the (slightly padded) box in
// its body frame; all intervals closed, so grazing an edge or a corner counts as touching.
bool OrientedBox::intersectsSegment(const Vec3& a, const Vec3& b) const {
  if (!a.allFinite() || !b.allFinite()) return false;
  double cy, sy;
  cosSin(yaw, &cy, &sy);
  return intersectsSegment(a, b, cy, sy);
}

bool OrientedBox::intersectsSegment(const Vec3& a, const Vec3& b, double cy, double sy) const {
  if (!a.allFinite() || !b.allFinite()) return false;
  const double tol = boxTolerance(*this);
  // The vertical slab first: it needs no rotation, and a segment wholly above a box (a flight
  // over the rooftops) ends here. (The slabs' order does not change the answer: the interval
  // kept is their intersection with [0, 1].)
  const double hz = 0.5 * std::abs(size.z()) + tol;
  const double pz = a.z() - center.z(), dz = (b.z() - center.z()) - pz;
  double t0 = 0.0;
  double t1 = 1.0;
  if (dz == 0.0) {
    if (pz < -hz || pz > hz) return false;
  } else {
    double enter = (-hz - pz) / dz;
    double leave = (hz - pz) / dz;
    if (enter > leave) std::swap(enter, leave);
    t0 = std::max(t0, enter);
    t1 = std::min(t1, leave);
    if (t0 > t1) return false;
  }
  // toBody() for both ends, with one sine and cosine.
  auto body = [&](const Vec3& w) {
    const Vec3 q = w - center;
    return Vec3(cy * q.x() + sy * q.y(), -sy * q.x() + cy * q.y(), q.z());
  };
  const Vec3 p = body(a);
  const Vec3 d = body(b) - p;
  const Vec3 half = 0.5 * size.cwiseAbs() + Vec3::Constant(tol);
  for (int k = 0; k < 2; ++k) {
    if (d[k] == 0.0) {
      if (p[k] < -half[k] || p[k] > half[k]) return false;
      continue;
    }
    double enter = (-half[k] - p[k]) / d[k];
    double leave = (half[k] - p[k]) / d[k];
    if (enter > leave) std::swap(enter, leave);
    t0 = std::max(t0, enter);
    t1 = std::min(t1, leave);
    if (t0 > t1) return false;
  }
  return true;
}

namespace {

// Separating-axis test for two rectangles given by their corners (touching counts as overlap).
bool rectanglesOverlap(const std::array<Vec2, 4>& ca, const std::array<Vec2, 4>& cb) {
  for (const auto* c : {&ca, &cb}) {
    for (int k = 0; k < 2; ++k) {
      const Vec2 axis = (*c)[k + 1] - (*c)[k];
      double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
      for (const Vec2& p : ca) {
        const double d = axis.dot(p);
        amin = std::min(amin, d);
        amax = std::max(amax, d);
      }
      for (const Vec2& p : cb) {
        const double d = axis.dot(p);
        bmin = std::min(bmin, d);
        bmax = std::max(bmax, d);
      }
      const double tol = kEpsilon * std::max(1.0, axis.squaredNorm()) *
                         std::max(1.0, std::max(std::abs(amax), std::abs(bmax)));
      if (amax < bmin - tol || bmax < amin - tol) return false;
    }
  }
  return true;
}

double pointSegmentDistanceSq(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  double t = len2 > 0.0 ? (p - a).dot(ab) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return (a + t * ab - p).squaredNorm();
}

// Rectangles are convex: when they are apart, the closest pair is a corner of one and an edge
// of the other, so 32 corner-edge distances give the exact answer without building polygons.
double cornersDistance(const std::array<Vec2, 4>& ca, const std::array<Vec2, 4>& cb) {
  if (rectanglesOverlap(ca, cb)) return 0.0;
  double best = 1e300;
  for (int i = 0; i < 4; ++i) {
    const Vec2& a0 = ca[i];
    const Vec2& a1 = ca[(i + 1) % 4];
    const Vec2& b0 = cb[i];
    const Vec2& b1 = cb[(i + 1) % 4];
    for (int j = 0; j < 4; ++j) {
      best = std::min(best, pointSegmentDistanceSq(cb[j], a0, a1));
      best = std::min(best, pointSegmentDistanceSq(ca[j], b0, b1));
    }
  }
  return std::sqrt(best);
}

}  // namespace

double footprintDistance(const OrientedBox& a, const OrientedBox& b) {
  return cornersDistance(a.corners2(), b.corners2());
}

double footprintDistance(const OrientedBox& a, const OrientedBox& b, double cos_b, double sin_b) {
  return cornersDistance(a.corners2(), b.corners2(cos_b, sin_b));
}

bool footprintsOverlap(const OrientedBox& a, const OrientedBox& b) {
  return rectanglesOverlap(a.corners2(), b.corners2());
}

}  // namespace hameritt::geometry
