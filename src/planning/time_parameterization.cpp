#include "hameritt/planning/time_parameterization.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "hameritt/scenario/error.h"

namespace hameritt::planning {

using geometry::Vec3;

namespace {

void requirePositive(double v, const char* field) {
  if (!(v > 0 && std::isfinite(v))) {
    throw scenario::ConfigError(std::string("planning.speed.") + field +
                                ": expected a positive finite number, got " +
                                scenario::formatNumber(v));
  }
}

// One straight segment driven with a trapezoid: from v0 up to at most vc and down to v1 with
// acceleration a over length len. Time to reach arc length s (0 <= s <= len).
struct SegmentProfile {
  double len, v0, v1, vp, a, s1, s3;
  SegmentProfile(double len_, double v0_, double v1_, double vc, double a_)
      : len(len_), v0(v0_), v1(v1_), a(a_) {
    vp = std::min(vc, std::sqrt(std::max(0.0, (2 * a * len + v0 * v0 + v1 * v1) / 2)));
    vp = std::max(vp, std::max(v0, v1));
    s1 = std::min(len, (vp * vp - v0 * v0) / (2 * a));
    s3 = std::max(s1, len - (vp * vp - v1 * v1) / (2 * a));
  }
  double timeAt(double s) const {
    double t = 0.0;
    const double sa = std::min(s, s1);
    t += (std::sqrt(v0 * v0 + 2 * a * sa) - v0) / a;
    if (s <= s1) return t;
    const double sc = std::min(s, s3) - s1;
    if (vp > 0) t += sc / vp;
    if (s <= s3) return t;
    const double sd = s - s3;
    const double vstart = vp;
    const double vend = std::sqrt(std::max(0.0, vstart * vstart - 2 * a * sd));
    t += (vstart - vend) / a;
    return t;
  }
};

}  // namespace

void SpeedLimits::validate() const {
  requirePositive(max_speed, "max_speed");
  requirePositive(climb_rate, "climb_rate");
  requirePositive(descent_rate, "descent_rate");
  requirePositive(accel, "accel");
}

double pathLength(const std::vector<Vec3>& p) {
  double l = 0.0;
  for (std::size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
  return l;
}

scenario::Trajectory timeParameterize(const std::vector<Vec3>& polyline, double t0,
                                      const SpeedLimits& limits, double sample_spacing,
                                      double initial_yaw) {
  limits.validate();
  if (polyline.empty()) throw std::invalid_argument("timeParameterize: empty polyline");
  if (!(sample_spacing > 0)) throw std::invalid_argument("timeParameterize: sample_spacing <= 0");
  // Drop repeated points.
  std::vector<Vec3> p{polyline.front()};
  for (std::size_t i = 1; i < polyline.size(); ++i) {
    if ((polyline[i] - p.back()).norm() > 1e-3) p.push_back(polyline[i]);
  }
  using scenario::roundMilli;
  scenario::Trajectory out;
  if (p.size() == 1) {
    out.push_back({roundMilli(t0), roundMilli(p[0].x()), roundMilli(p[0].y()), roundMilli(p[0].z()),
                   roundMilli(initial_yaw)});
    return out;
  }
  const std::size_t n = p.size() - 1;  // segments
  std::vector<double> len(n), cap(n), yaw(n);
  double last_yaw = initial_yaw;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = p[i + 1] - p[i];
    len[i] = d.norm();
    const double h = d.head<2>().norm();
    double c = std::numeric_limits<double>::infinity();
    if (h > 1e-9) c = std::min(c, limits.max_speed * len[i] / h);
    if (d.z() > 1e-9) c = std::min(c, limits.climb_rate * len[i] / d.z());
    if (d.z() < -1e-9) c = std::min(c, limits.descent_rate * len[i] / -d.z());
    cap[i] = c;
    if (h > 1e-6) last_yaw = std::atan2(d.y(), d.x());
    yaw[i] = last_yaw;
  }
  // Vertex speeds: rest at both ends, corners limited by the turn.
  std::vector<double> v(n + 1, 0.0);
  for (std::size_t i = 1; i < n; ++i) {
    const Vec3 d0 = (p[i] - p[i - 1]) / len[i - 1], d1 = (p[i + 1] - p[i]) / len[i];
    const double c = std::clamp(d0.dot(d1), -1.0, 1.0);
    v[i] = std::min(cap[i - 1], cap[i]) * (1 + c) / 2;
  }
  const double a = limits.accel;
  for (std::size_t i = 0; i < n; ++i)
    v[i + 1] = geometry::minSqrt(v[i + 1], v[i] * v[i] + 2 * a * len[i]);
  for (std::size_t i = n; i-- > 0;)
    v[i] = geometry::minSqrt(v[i], v[i + 1] * v[i + 1] + 2 * a * len[i]);

  double t = t0;
  auto emit = [&](const Vec3& q, double time, double heading) {
    scenario::TrajectoryPoint pt{roundMilli(time), roundMilli(q.x()), roundMilli(q.y()),
                                 roundMilli(q.z()), roundMilli(heading)};
    // Keep every sample (a corner must not be cut) with strictly increasing times.
    if (!out.empty() && !(pt.t > out.back().t)) pt.t = roundMilli(out.back().t + 1e-3);
    out.push_back(pt);
  };
  emit(p[0], t, yaw[0]);
  for (std::size_t i = 0; i < n; ++i) {
    const SegmentProfile prof(len[i], v[i], v[i + 1], cap[i], a);
    const int k = std::max(1, static_cast<int>(std::ceil(len[i] / sample_spacing)));
    for (int j = 1; j <= k; ++j) {
      const double s = len[i] * j / k;
      const Vec3 q = j == k ? p[i + 1] : Vec3(p[i] + (p[i + 1] - p[i]) * (s / len[i]));
      const double h = i + 1 < n && j == k ? yaw[i + 1] : yaw[i];
      emit(q, t + prof.timeAt(s), h);
    }
    t += prof.timeAt(len[i]);
  }
  return out;
}

}  // namespace hameritt::planning
