#include "hameritt/planning/validity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <utility>

#include "hameritt/geometry/segment.h"
#include "hameritt/scenario/error.h"

namespace hameritt::planning {

using geometry::Vec2;
using geometry::Vec3;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Distance in the plane from the segment [a, b] to the polygon region (0 when they touch).
double segmentPolygonDistance(const geometry::Polygon& poly, const Vec2& a, const Vec2& b) {
  if (poly.intersectsSegment(a, b)) return 0.0;
  const auto& v = poly.vertices();
  double d = kInf;
  for (std::size_t i = 0; i < v.size(); ++i) {
    d = std::min(d, geometry::segmentSegmentDistance(a, b, v[i], v[(i + 1) % v.size()]));
  }
  return d;
}

geometry::OrientedBox inflate(const geometry::OrientedBox& b, double m) {
  geometry::OrientedBox o = b;
  o.size += Vec3(2 * m, 2 * m, 2 * m);
  return o;
}

// Intersects [*lo, *hi] with the parameters u in [0, 1] where f(u) = fa + (fb - fa) u lies in
// [flo, fhi].
void clip(double fa, double fb, double flo, double fhi, double* lo, double* hi) {
  const double d = fb - fa;
  if (std::abs(d) < 1e-12) {
    if (fa < flo || fa > fhi) *hi = -1.0;  // empty
    return;
  }
  double u0 = (flo - fa) / d, u1 = (fhi - fa) / d;
  if (u0 > u1) std::swap(u0, u1);
  *lo = std::max(*lo, u0);
  *hi = std::min(*hi, u1);
}

}  // namespace

void ValiditySettings::validate() const {
  if (!(margin >= 0.1 && margin <= 20.0)) {
    throw scenario::ConfigError("planning.margin: expected metres in [0.1, 20], got " +
                                scenario::formatNumber(margin));
  }
  if (!(altitude_min >= 0.0 && std::isfinite(altitude_min))) {
    throw scenario::ConfigError("planning.altitude_min: expected a finite number >= 0, got " +
                                scenario::formatNumber(altitude_min));
  }
  if (!(altitude_max > altitude_min && std::isfinite(altitude_max))) {
    throw scenario::ConfigError("planning.altitude_max: expected a finite number > altitude_min (" +
                                scenario::formatNumber(altitude_min) + "), got " +
                                scenario::formatNumber(altitude_max));
  }
}

// The inflated obstacles and, for point queries, a grid whose cells list every box whose
// footprint's bounding rectangle (padded by 1 mm) meets the cell.
struct WorldValidity::Obstacles {
  geometry::OccluderIndex index{20.0};
  double cell = 10.0;
  Vec2 origin{0, 0};
  int nx = 0, ny = 0;
  std::vector<std::vector<int>> grid;

  // The grid cell holding q, or nullptr off the grid.
  const std::vector<int>* at(const Vec2& q) const {
    const double fx = (q.x() - origin.x()) / cell, fy = (q.y() - origin.y()) / cell;
    if (!(fx >= 0 && fy >= 0 && fx < nx && fy < ny)) return nullptr;
    return &grid[static_cast<std::size_t>(static_cast<int>(fy) * nx + static_cast<int>(fx))];
  }
};

namespace {

// The inflated boxes near a run of trajectory samples, for checkTrajectory().
class SegmentBoxes {
 public:
  // Collects the boxes whose bounds meet those of samples `first`.. (at most kSamples of them
  // within kSpan metres in x and y), padded by kPad; returns the last sample of the run.
  std::size_t collect(const WorldValidity::Obstacles& o, const scenario::Trajectory& traj,
                      std::size_t first) {
    constexpr std::size_t kSamples = 64;
    constexpr double kSpan = 24.0;
    Vec2 lo(traj[first].x, traj[first].y), hi = lo;
    std::size_t last = first;
    while (last + 1 < traj.size() && last + 1 - first < kSamples) {
      const Vec2 q(traj[last + 1].x, traj[last + 1].y);
      const Vec2 nlo = lo.cwiseMin(q), nhi = hi.cwiseMax(q);
      if (last > first && (nhi - nlo).maxCoeff() > kSpan) break;
      lo = nlo;
      hi = nhi;
      ++last;
    }
    boxes_.clear();
    for (int i :
         o.index.candidates(geometry::Aabb2{lo - Vec2(kPad, kPad), hi + Vec2(kPad, kPad)})) {
      const geometry::OrientedBox& b = o.index.box(i);
      boxes_.push_back({b, b.bounds2(), o.index.trig(i)});
    }
    return last;
  }
  // staticSegmentValid's obstacle test with slack > 0 for a segment of the run: the same boxes
  // (bounds overlapping the segment's), the same test.
  bool clear(const Vec3& a, const Vec3& b, double slack) const {
    const geometry::Aabb2 box{a.head<2>().cwiseMin(b.head<2>()), a.head<2>().cwiseMax(b.head<2>())};
    for (const Near& n : boxes_) {
      if (!n.bounds.overlaps(box)) continue;
      geometry::OrientedBox o = n.box;
      o.size -= Vec3(2 * slack, 2 * slack, 2 * slack);
      if (o.intersectsSegment(a, b, n.trig.first, n.trig.second)) return false;
    }
    return true;
  }

 private:
  // Rounding margin of the run's bounds (each segment then filters exactly).
  static constexpr double kPad = 1e-3;
  struct Near {
    geometry::OrientedBox box;
    geometry::Aabb2 bounds;
    std::pair<double, double> trig;  // std::cos, std::sin of box.yaw
  };
  std::vector<Near> boxes_;
};

// The world's obstacles inflated by `margin`, built once per world fingerprint and margin and
// shared (immutable) between checkers and threads; the last few are kept.
std::shared_ptr<const WorldValidity::Obstacles> inflatedObstacles(const scenario::World& world,
                                                                  double margin) {
  using Obstacles = WorldValidity::Obstacles;
  static std::mutex mutex;
  static std::map<std::pair<std::uint64_t, double>, std::shared_ptr<const Obstacles>> cache;
  const auto key = std::make_pair(world.fingerprint(), margin);
  std::lock_guard<std::mutex> lock(mutex);
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  auto o = std::make_shared<Obstacles>();
  const auto& occ = world.occluders();
  for (std::size_t i = 0; i < occ.size(); ++i) {
    o->index.add(inflate(occ.box(static_cast<int>(i)), margin));
  }
  o->index.build();
  const auto b = world.bounds();
  o->origin = b.min - Vec2(o->cell, o->cell);
  o->nx = static_cast<int>(std::ceil((b.max.x() - o->origin.x()) / o->cell)) + 2;
  o->ny = static_cast<int>(std::ceil((b.max.y() - o->origin.y()) / o->cell)) + 2;
  o->grid.resize(static_cast<std::size_t>(o->nx * o->ny));
  auto clampX = [&](double v) {
    return std::clamp(static_cast<int>(std::floor((v - o->origin.x()) / o->cell)), 0, o->nx - 1);
  };
  auto clampY = [&](double v) {
    return std::clamp(static_cast<int>(std::floor((v - o->origin.y()) / o->cell)), 0, o->ny - 1);
  };
  for (std::size_t i = 0; i < o->index.size(); ++i) {
    const auto corners = o->index.box(static_cast<int>(i)).corners2();
    Vec2 lo = corners[0], hi = corners[0];
    for (const auto& c : corners) {
      lo = lo.cwiseMin(c);
      hi = hi.cwiseMax(c);
    }
    for (int y = clampY(lo.y() - 1e-3); y <= clampY(hi.y() + 1e-3); ++y) {
      for (int x = clampX(lo.x() - 1e-3); x <= clampX(hi.x() + 1e-3); ++x) {
        o->grid[static_cast<std::size_t>(y * o->nx + x)].push_back(static_cast<int>(i));
      }
    }
  }
  if (cache.size() >= 8) cache.clear();
  cache.emplace(key, o);
  return o;
}

}  // namespace

ValiditySettings validitySettingsFor(const scenario::UavSpec& uav, double margin) {
  ValiditySettings s;
  s.margin = margin;
  s.altitude_min = uav.altitude_min;
  s.altitude_max = uav.altitude_max;
  return s;
}

WorldValidity::WorldValidity(const scenario::World& world, const scenario::Mission& mission,
                             const ValiditySettings& settings)
    : WorldValidity(world, mission.kozs, settings) {}

WorldValidity::WorldValidity(const scenario::World& world, std::vector<scenario::KeepOutZone> kozs,
                             const ValiditySettings& settings)
    : world_(world), kozs_(std::move(kozs)), settings_(settings), bounds_(world.bounds()) {
  settings_.validate();
  obstacles_ = inflatedObstacles(world, settings_.margin);
  for (std::size_t i = 0; i < kozs_.size(); ++i) {
    if (kozs_[i].polygon.size() < 3) {
      throw scenario::ConfigError("planning.keep_out_zones[" + std::to_string(i) +
                                  "].polygon: expected at least 3 vertices");
    }
    geometry::Aabb2 b = kozs_[i].polygon.bounds();
    b.min -= Vec2(settings_.margin, settings_.margin);
    b.max += Vec2(settings_.margin, settings_.margin);
    koz_bounds_.push_back(b);
  }
}

bool WorldValidity::hasTimedKozs() const {
  for (const auto& k : kozs_) {
    if (!k.window.unbounded()) return true;
  }
  return false;
}

bool WorldValidity::staticValid(const Vec3& p, double slack) const {
  if (!p.allFinite()) return false;
  if (p.z() < settings_.altitude_min || p.z() > settings_.altitude_max) return false;
  if (!bounds_.contains(p.head<2>())) return false;
  const Vec2 q = p.head<2>();
  const geometry::OccluderIndex& index = obstacles_->index;
  auto inside = [&](int i) {
    geometry::OrientedBox b = index.box(i);
    if (slack > 0) b.size -= Vec3(2 * slack, 2 * slack, 2 * slack);
    const auto& [c, s] = index.trig(i);
    return b.contains(p, c, s);
  };
  if (const std::vector<int>* cell = obstacles_->at(q)) {
    for (int i : *cell) {
      if (inside(i)) return false;
    }
    return true;
  }
  for (int i : index.candidates(geometry::Aabb2{q, q})) {
    if (inside(i)) return false;
  }
  return true;
}

bool WorldValidity::staticSegmentValid(const Vec3& a, const Vec3& b, double slack) const {
  // The band and the bounds are convex: the endpoints decide.
  if (!staticValid(a, slack) || !staticValid(b, slack)) return false;
  return obstacleSegmentClear(a, b, std::max(0.0, slack));
}

bool WorldValidity::obstacleSegmentClear(const Vec3& a, const Vec3& b, double slack) const {
  if (slack == 0) return obstacles_->index.clear(a, b);
  // A negative slack grows the boxes: the candidates are looked up that much wider.
  const Vec2 pad = Vec2::Constant(std::max(0.0, -slack));
  geometry::Aabb2 box{a.head<2>().cwiseMin(b.head<2>()) - pad,
                      a.head<2>().cwiseMax(b.head<2>()) + pad};
  for (int i : obstacles_->index.candidates(box)) {
    geometry::OrientedBox o = obstacles_->index.box(i);
    o.size -= Vec3(2 * slack, 2 * slack, 2 * slack);
    const auto& [c, s] = obstacles_->index.trig(i);
    if (o.intersectsSegment(a, b, c, s)) return false;
  }
  return true;
}

bool WorldValidity::kozSegmentHit(const scenario::KeepOutZone& k, std::size_t i, const Vec3& a,
                                  const Vec3& b, double u0, double u1, double slack) const {
  const double m = std::max(0.0, settings_.margin - slack);
  const double zlo = k.alt_min ? *k.alt_min - m : -kInf;
  const double zhi = k.alt_max ? *k.alt_max + m : kInf;
  clip(a.z(), b.z(), zlo, zhi, &u0, &u1);
  if (u0 > u1) return false;
  const Vec3 pa = a + (b - a) * u0, pb = a + (b - a) * u1;
  const Vec2 qa = pa.head<2>(), qb = pb.head<2>();
  const geometry::Aabb2 sb{qa.cwiseMin(qb), qa.cwiseMax(qb)};
  if (!sb.overlaps(koz_bounds_[i])) return false;
  return segmentPolygonDistance(k.polygon, qa, qb) <= m;
}

bool WorldValidity::kozClear(const Vec3& p, double t0, double t1, double slack) const {
  return kozSegmentClearDuring(p, p, t0, t1, slack);
}

bool WorldValidity::kozSegmentClear(const Vec3& a, const Vec3& b, double ta, double tb,
                                    double slack) const {
  for (std::size_t i = 0; i < kozs_.size(); ++i) {
    const auto& k = kozs_[i];
    double u0 = 0.0, u1 = 1.0;
    clip(ta, tb, k.window.net ? *k.window.net : -kInf, k.window.nlt ? *k.window.nlt : kInf, &u0,
         &u1);
    if (u0 > u1) continue;
    if (kozSegmentHit(k, i, a, b, u0, u1, slack)) return false;
  }
  return true;
}

bool WorldValidity::kozSegmentClearDuring(const Vec3& a, const Vec3& b, double t0, double t1,
                                          double slack) const {
  for (std::size_t i = 0; i < kozs_.size(); ++i) {
    const auto& k = kozs_[i];
    if (!k.window.overlaps(t0, t1)) continue;
    if (kozSegmentHit(k, i, a, b, 0.0, 1.0, slack)) return false;
  }
  return true;
}

std::string WorldValidity::explain(const Vec3& p, double t) const {
  char buf[160];
  std::snprintf(buf, sizeof(buf), "(%.3f, %.3f, %.3f) at t = %.3f s", p.x(), p.y(), p.z(), t);
  const std::string where = buf;
  if (!p.allFinite()) return where + ": not finite";
  if (p.z() < settings_.altitude_min || p.z() > settings_.altitude_max) {
    return where + ": outside the altitude band [" +
           scenario::formatNumber(settings_.altitude_min) + ", " +
           scenario::formatNumber(settings_.altitude_max) + "]";
  }
  if (!bounds_.contains(p.head<2>())) return where + ": outside the neighborhood bounds";
  const Vec2 q = p.head<2>();
  for (int i : obstacles_->index.candidates(geometry::Aabb2{q, q})) {
    if (obstacles_->index.box(i).contains(p)) {
      return where + ": inside the box of " +
             world_.entities()[static_cast<std::size_t>(world_.occluderOwner(i))].id +
             " inflated by " + scenario::formatNumber(settings_.margin) + " m";
    }
  }
  for (std::size_t i = 0; i < kozs_.size(); ++i) {
    if (kozs_[i].window.active(t) && kozSegmentHit(kozs_[i], i, p, p, 0.0, 1.0, 0.0)) {
      return where + ": inside keep-out zone " + kozs_[i].id + " (active)";
    }
  }
  return "";
}

std::string WorldValidity::checkTrajectory(const scenario::Trajectory& traj, double max_step,
                                           double slack) const {
  if (traj.empty()) return "empty trajectory";
  auto pos = [](const scenario::TrajectoryPoint& p) { return Vec3(p.x, p.y, p.z); };
  if (!staticValid(pos(traj[0]), slack) || !kozClear(pos(traj[0]), traj[0].t, traj[0].t, slack)) {
    return "sample 0: " + explain(pos(traj[0]), traj[0].t);
  }
  // staticSegmentValid() over runs of consecutive samples: the boxes near a run are looked up
  // once and each segment tests those whose bounds meet its own, as staticSegmentValid does;
  // an end point's check is reused by the next segment.
  SegmentBoxes run;
  std::size_t run_end = 0;  // last sample of the current run
  bool a_valid = true;      // staticValid of sample i - 1 (sample 0 checked above)
  for (std::size_t i = 1; i < traj.size(); ++i) {
    const Vec3 a = pos(traj[i - 1]), b = pos(traj[i]);
    const double ta = traj[i - 1].t, tb = traj[i].t;
    if (!(tb > ta)) return "sample " + std::to_string(i) + ": time not increasing";
    if (i > run_end) run_end = run.collect(*obstacles_, traj, i - 1);
    const bool b_valid = staticValid(b, slack);
    const bool static_ok =
        a_valid && b_valid && (slack <= 0 ? obstacles_->index.clear(a, b) : run.clear(a, b, slack));
    a_valid = b_valid;
    // Both checks are exact over a whole segment, so a valid segment needs no pieces; the
    // pieces only locate a failure for the message.
    if (static_ok && kozSegmentClear(a, b, ta, tb, slack)) continue;
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / max_step)));
    for (int k = 0; k < n; ++k) {
      const double u0 = static_cast<double>(k) / n, u1 = static_cast<double>(k + 1) / n;
      const Vec3 p0 = a + (b - a) * u0, p1 = a + (b - a) * u1;
      const double t0 = ta + (tb - ta) * u0, t1 = ta + (tb - ta) * u1;
      if (!staticSegmentValid(p0, p1, slack) || !kozSegmentClear(p0, p1, t0, t1, slack)) {
        std::string why = explain(p1, t1);
        if (why.empty()) why = explain(p0, t0);
        if (why.empty()) why = "segment crosses an obstacle or an active keep-out zone";
        return "segment " + std::to_string(i - 1) + "-" + std::to_string(i) + ": " + why;
      }
    }
    return "segment " + std::to_string(i - 1) + "-" + std::to_string(i) +
           ": segment crosses an obstacle or an active keep-out zone";
  }
  return "";
}

}  // namespace hameritt::planning
