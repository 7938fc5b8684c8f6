#include "hameritt/scenario/trajectory.h"

#include <algorithm>
#include <cmath>

#include "hameritt/geometry/segment.h"

namespace hameritt::scenario {

using geometry::Vec2;
using geometry::Vec3;

TrajectoryPoint sampleTrajectory(const Trajectory& traj, double t) {
  if (traj.empty()) return {};
  if (t <= traj.front().t) return traj.front();
  if (t >= traj.back().t) return traj.back();
  return sampleTrajectoryIn(traj, t, 1, traj.size());
}

TrajectoryPoint sampleTrajectoryIn(const Trajectory& traj, double t, std::size_t lo,
                                   std::size_t hi) {
  const auto it =
      std::upper_bound(traj.begin() + static_cast<std::ptrdiff_t>(lo),
                       traj.begin() + static_cast<std::ptrdiff_t>(hi), t,
                       [](double v, const TrajectoryPoint& p) { return v < p.t; });
  const TrajectoryPoint& b = *it;
  const TrajectoryPoint& a = *(it - 1);
  const double span = b.t - a.t;
  const double u = span > 0 ? (t - a.t) / span : 1.0;
  TrajectoryPoint p;
  p.t = t;
  p.x = a.x + u * (b.x - a.x);
  p.y = a.y + u * (b.y - a.y);
  p.z = a.z + u * (b.z - a.z);
  p.yaw = geometry::wrapPi(a.yaw + u * geometry::wrapPi(b.yaw - a.yaw));
  return p;
}

geometry::OrientedBox poseBox(const geometry::OrientedBox& box, const TrajectoryPoint& p) {
  geometry::OrientedBox b = box;
  b.center = Vec3(p.x, p.y, p.z + 0.5 * box.size.z());
  b.yaw = p.yaw;
  return b;
}

namespace {

struct Vertex {
  Vec3 p;
  double vmax;
};

TrajectoryPoint rounded(double t, const Vec3& p, double yaw) {
  return {roundMilli(t), roundMilli(p.x()), roundMilli(p.y()), roundMilli(p.z()),
          roundMilli(geometry::wrapPi(yaw))};
}

// Intersection of the lines p + s*d and q + r*e, if not near-parallel.
std::optional<Vec2> lineCross(const Vec2& p, const Vec2& d, const Vec2& q, const Vec2& e) {
  const double den = geometry::cross2(d, e);
  if (std::abs(den) < 1e-6) return std::nullopt;
  return p + (geometry::cross2(q - p, e) / den) * d;
}

}  // namespace

Trajectory planDrive(const std::vector<Vec2>& path, const DriveSpec& spec) {
  std::vector<Vertex> vs;
  const std::size_t edges = path.size() - 1;
  double start = spec.start_offset;
  if (spec.from_kerb) start += 8.0;  // room to pull out
  for (std::size_t i = 0; i < edges; ++i) {
    const Vec2 a = path[i], b = path[i + 1];
    const double len = (b - a).norm();
    const Vec2 u = (b - a) / len;
    const Vec2 r(u.y(), -u.x());
    const double s0 = i == 0 ? std::clamp(start, 0.0, std::max(0.0, len - spec.corner_clearance - 1.0))
                             : spec.corner_clearance;
    const double s1 = std::max(s0 + 1.0, len - spec.corner_clearance);
    const Vec2 p0 = a + u * s0 + r * spec.lane_offset;
    const Vec2 p1 = a + u * s1 + r * spec.lane_offset;
    if (i > 0) {
      // Quadratic Bezier through the intersection from the previous lane end.
      const Vec2 prev = vs.back().p.head<2>();
      const Vec2 pu = (path[i] - path[i - 1]).normalized();
      const auto c = lineCross(prev, pu, p0, u);
      const double turn = std::abs(geometry::wrapPi(std::atan2(u.y(), u.x()) - std::atan2(pu.y(), pu.x())));
      if (c && turn > 0.2) {
        for (double k : {0.25, 0.5, 0.75}) {
          const Vec2 q = (1 - k) * (1 - k) * prev + 2 * k * (1 - k) * (*c) + k * k * p0;
          vs.push_back({Vec3(q.x(), q.y(), 0.0), spec.turn_speed});
        }
      }
    }
    vs.push_back({Vec3(p0.x(), p0.y(), 0.0), spec.cruise_speed});
    vs.push_back({Vec3(p1.x(), p1.y(), 0.0), spec.cruise_speed});
  }
  if (spec.from_kerb) vs.insert(vs.begin(), {*spec.from_kerb, 0.0});
  // Subdivide long segments so that acceleration ramps are represented.
  std::vector<Vertex> fine{vs.front()};
  for (std::size_t i = 1; i < vs.size(); ++i) {
    const Vec3 a = fine.back().p, b = vs[i].p;
    const double len = (b - a).norm();
    if (len < 1e-6) continue;
    const int pieces = std::max(1, static_cast<int>(std::ceil(len / 12.0)));
    for (int k = 1; k < pieces; ++k) fine.push_back({a + (b - a) * (double(k) / pieces), spec.cruise_speed});
    fine.push_back(vs[i]);
  }
  fine.front().vmax = 0.0;
  fine.back().vmax = 0.0;
  const std::size_t n = fine.size();
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = fine[i].vmax;
  for (std::size_t i = 1; i < n; ++i) {
    const double l = (fine[i].p - fine[i - 1].p).norm();
    v[i] = geometry::minSqrt(v[i], v[i - 1] * v[i - 1] + 2 * spec.accel * l);
  }
  for (std::size_t i = n - 1; i-- > 0;) {
    const double l = (fine[i + 1].p - fine[i].p).norm();
    v[i] = geometry::minSqrt(v[i], v[i + 1] * v[i + 1] + 2 * spec.decel * l);
  }
  // Times from the average speed on each piece (exact for constant acceleration).
  std::vector<double> t(n);
  t[0] = spec.start_time + spec.depart_delay;
  for (std::size_t i = 1; i < n; ++i) {
    const double l = (fine[i].p - fine[i - 1].p).norm();
    const double avg = std::max(0.5 * (v[i] + v[i - 1]), 0.05);
    t[i] = t[i - 1] + l / avg;
  }
  // Heading at each vertex, computed once (each is asked for up to four times below).
  std::vector<double> headings(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = i + 1 < n ? fine[i + 1].p - fine[i].p : fine[i].p - fine[i - 1].p;
    headings[i] = std::atan2(d.y(), d.x());
  }
  auto heading = [&](std::size_t i) { return headings[i]; };
  Trajectory out;
  const double yaw0 = spec.from_kerb ? spec.from_kerb_yaw : heading(0);
  // A waiting point only where the delay survives rounding to milliseconds (else two points
  // would share t).
  if (roundMilli(t[0]) > roundMilli(spec.start_time)) {
    out.push_back(rounded(spec.start_time, fine[0].p, yaw0));
  }
  out.push_back(rounded(t[0], fine[0].p, yaw0));
  for (std::size_t i = 1; i < n; ++i) {
    // Drop points where speed and heading do not change: interpolation is identical.
    if (i + 1 < n && std::abs(v[i] - v[i - 1]) < 0.01 && std::abs(v[i + 1] - v[i]) < 0.01 &&
        std::abs(geometry::wrapPi(heading(i) - heading(i - 1))) < 1e-6) {
      continue;
    }
    // Mean of the incoming and outgoing headings, along the shorter arc.
    const double yaw = i + 1 < n ? heading(i - 1) + 0.5 * geometry::wrapPi(heading(i) - heading(i - 1))
                                 : heading(i - 1);
    TrajectoryPoint p = rounded(t[i], fine[i].p, yaw);
    if (p.t <= out.back().t) p.t = out.back().t + 0.001;
    out.push_back(p);
  }
  return out;
}

Trajectory walkRing(const std::vector<Vec2>& ring, double s0, double s1, double speed, double t0) {
  const double len = geometry::polylineLength(ring);
  auto wrap = [len](double s) {
    double m = std::fmod(s, len);
    return m < 0 ? m + len : m;
  };
  // Cumulative arc length at each ring vertex.
  std::vector<double> cum{0.0};
  for (std::size_t i = 1; i < ring.size(); ++i) cum.push_back(cum.back() + (ring[i] - ring[i - 1]).norm());
  // Ring vertices passed on the way (at arc lengths cum[k] + m * len strictly between s0 and
  // s1), in walking order.
  const double lo = std::min(s0, s1), hi = std::max(s0, s1);
  std::vector<double> passed;
  for (std::size_t k = 0; k + 1 < cum.size(); ++k) {
    for (double m = std::floor((lo - cum[k]) / len); cum[k] + m * len < hi; m += 1.0) {
      const double v = cum[k] + m * len;
      if (v > lo + 1e-6 && v < hi - 1e-6) passed.push_back(v);
    }
  }
  std::sort(passed.begin(), passed.end());
  if (s1 < s0) std::reverse(passed.begin(), passed.end());
  std::vector<double> stops{s0};
  stops.insert(stops.end(), passed.begin(), passed.end());
  stops.push_back(s1);
  Trajectory out;
  auto pos = [&](double s) { return geometry::polylinePointAt(ring, wrap(s)); };
  auto yawAt = [&](std::size_t i) {
    const Vec2 a = pos(stops[std::min(i, stops.size() - 2)]);
    const Vec2 b = pos(stops[std::min(i + 1, stops.size() - 1)]);
    return std::atan2((b - a).y(), (b - a).x());
  };
  const Vec2 p0 = pos(s0);
  if (t0 > 0) out.push_back(rounded(0.0, Vec3(p0.x(), p0.y(), 0.0), yawAt(0)));
  for (std::size_t i = 0; i < stops.size(); ++i) {
    const Vec2 p = pos(stops[i]);
    const double t = t0 + std::abs(stops[i] - s0) / speed;
    TrajectoryPoint q = rounded(t, Vec3(p.x(), p.y(), 0.0), yawAt(i == stops.size() - 1 ? i - 1 : i));
    if (!out.empty() && q.t <= out.back().t) {
      if (i == 0) continue;
      q.t = out.back().t + 0.001;
    }
    out.push_back(q);
  }
  return out;
}

std::optional<std::pair<double, double>> insideInterval(const Trajectory& traj,
                                                        const geometry::Polygon& convex) {
  const geometry::Polygon poly = convex.counterClockwise();
  const auto& v = poly.vertices();
  std::optional<double> enter, exit;
  for (std::size_t i = 0; i + 1 < traj.size(); ++i) {
    const Vec2 a(traj[i].x, traj[i].y), b(traj[i + 1].x, traj[i + 1].y);
    // Cyrus-Beck clipping of the segment against the convex polygon.
    double lo = 0.0, hi = 1.0;
    bool empty = false;
    const Vec2 d = b - a;
    for (std::size_t k = 0; k < v.size() && !empty; ++k) {
      const Vec2 e0 = v[k], e1 = v[(k + 1) % v.size()];
      const Vec2 edge = e1 - e0;
      const double num = geometry::cross2(edge, a - e0);   // >= 0 inside
      const double den = geometry::cross2(edge, d);
      if (std::abs(den) < 1e-15) {
        if (num < 0) empty = true;
        continue;
      }
      const double s = -num / den;
      if (den > 0) lo = std::max(lo, s);
      else hi = std::min(hi, s);
      if (lo > hi) empty = true;
    }
    const double ta = traj[i].t, tb = traj[i + 1].t;
    if (empty) {
      if (enter) break;
      continue;
    }
    const double t_in = ta + lo * (tb - ta), t_out = ta + hi * (tb - ta);
    if (!enter) enter = t_in;
    exit = t_out;
    if (hi < 1.0) break;  // left the polygon inside this segment
  }
  if (!enter) return std::nullopt;
  return std::make_pair(*enter, *exit);
}

std::vector<ScenarioEntity> aircraftEntities(const SimConfig& config) {
  std::vector<ScenarioEntity> out;
  for (const auto& a : config.aircraft) {
    if (a.trajectory.empty()) continue;
    ScenarioEntity se;
    se.entity.id = a.id;
    se.entity.cls = EntityClass::kAircraft;
    se.entity.attributes.set("model", a.model);
    se.role = "aircraft";
    for (auto p : a.trajectory) {
      p.z -= 0.5 * a.size.z();
      se.trajectory.push_back(p);
    }
    const auto& p0 = se.trajectory.front();
    se.entity.box = boxFromPose(geometry::Vec3(p0.x, p0.y, p0.z), p0.yaw, a.size);
    out.push_back(std::move(se));
  }
  return out;
}

}  // namespace hameritt::scenario
