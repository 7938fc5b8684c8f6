#include "hameritt/planning/chase.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "hameritt/planning/look_at.h"
#include "hameritt/scenario/entity.h"
#include "hameritt/scenario/error.h"

namespace hameritt::planning {

using geometry::Vec2;
using geometry::Vec3;

void ChaseSettings::validate() const {
  auto need = [](bool ok, const char* f, const std::string& what, double v) {
    if (!ok) {
      throw scenario::ConfigError(std::string("chase.") + f + ": expected " + what + ", got " +
                                  scenario::formatNumber(v));
    }
  };
  need(std::isfinite(behind) && behind >= 0, "behind", "metres >= 0", behind);
  need(std::isfinite(height) && height > 0, "height", "metres > 0", height);
  need(step > 0 && step <= 5, "step", "seconds in (0, 5]", step);
  need(time_constant >= step, "time_constant", "seconds >= step", time_constant);
  need(caught_radius > 0, "caught_radius", "metres > 0", caught_radius);
}

namespace {

// The target's ground path as the simulator plays it (linear between keyframes): positions and
// the arc length reached at each keyframe.
class GroundPath {
 public:
  explicit GroundPath(const scenario::Trajectory& traj) : traj_(traj) {
    arc_.push_back(0.0);
    for (std::size_t i = 1; i < traj.size(); ++i) {
      arc_.push_back(arc_.back() + (xy(i) - xy(i - 1)).norm());
    }
  }
  // Arc length reached at time t.
  double arcAt(double t) const {
    if (traj_.size() < 2 || t <= traj_.front().t) return 0.0;
    for (std::size_t i = 1; i < traj_.size(); ++i) {
      if (t <= traj_[i].t) {
        const double dt = traj_[i].t - traj_[i - 1].t;
        const double u = dt > 0 ? (t - traj_[i - 1].t) / dt : 1.0;
        return arc_[i - 1] + u * (arc_[i] - arc_[i - 1]);
      }
    }
    return arc_.back();
  }
  // Ground point at arc length s (before the start: back along the first heading).
  Vec3 pointAt(double s) const {
    const auto& f = traj_.front();
    if (s <= 0.0 || traj_.size() < 2) {
      return Vec3(f.x + s * std::cos(f.yaw), f.y + s * std::sin(f.yaw), f.z);
    }
    for (std::size_t i = 1; i < traj_.size(); ++i) {
      if (s <= arc_[i]) {
        const double len = arc_[i] - arc_[i - 1];
        const double u = len > 0 ? (s - arc_[i - 1]) / len : 1.0;
        const auto& a = traj_[i - 1];
        const auto& b = traj_[i];
        return Vec3(a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), a.z + u * (b.z - a.z));
      }
    }
    const auto& l = traj_.back();
    return Vec3(l.x, l.y, l.z);
  }

 private:
  Vec2 xy(std::size_t i) const { return Vec2(traj_[i].x, traj_[i].y); }
  const scenario::Trajectory& traj_;
  std::vector<double> arc_;
};

constexpr double kEdge = 2.0;  // metres kept from the area's bounds

Vec3 clampNorm2(const Vec3& v, double max) {
  const double n = v.head<2>().norm();
  if (n <= max || n == 0.0) return v;
  Vec3 out = v;
  out.head<2>() *= max / n;
  return out;
}

}  // namespace

ChaseResult planChasePath(const WorldValidity& validity, const scenario::CameraSpec& camera,
                          const Vec3& start, double t0, double t_end,
                          const scenario::Trajectory& target, const Vec3& target_size, double zmin,
                          double zmax, const UavPlannerSettings& settings,
                          const ChaseSettings& chase) {
  chase.validate();
  settings.speed.validate();
  ChaseResult r;
  if (target.empty()) {
    r.message = "the target has no trajectory";
    return r;
  }
  const GroundPath path(target);
  // The chase point at time t: `behind` metres back along the path, `height` above it, in the band.
  auto chasePoint = [&](double t) {
    Vec3 p = path.pointAt(path.arcAt(t) - chase.behind);
    p.z() = std::clamp(scenario::sampleTrajectory(target, t).z + chase.height, zmin, zmax);
    return p;
  };
  const auto& sp = settings.speed;
  Vec3 q = start, v = Vec3::Zero();
  auto keyframe = [&](double t) {
    const scenario::TrajectoryPoint tp = scenario::sampleTrajectory(target, t);
    const Vec2 d(tp.x - q.x(), tp.y - q.y());
    const double yaw = std::remainder(
        (d.norm() > 3.0 ? std::atan2(d.y(), d.x()) : tp.yaw) + chase.yaw_offset, 2 * geometry::kPi);
    return scenario::TrajectoryPoint{scenario::roundMilli(t), q.x(), q.y(), q.z(),
                                     scenario::roundMilli(yaw)};
  };
  // `c`: the chase point at the keyframe's time.
  auto judge = [&](const scenario::TrajectoryPoint& k, const Vec3& c) {
    if (!r.caught_t && (Vec3(k.x, k.y, k.z) - c).norm() <= chase.caught_radius) r.caught_t = k.t;
    if (!r.caught_t) return;
    const scenario::TrajectoryPoint tp = scenario::sampleTrajectory(target, k.t);
    const Vec3 centre(tp.x, tp.y, tp.z + 0.5 * target_size.z());
    const Vec3 pos(k.x, k.y, k.z);
    ++r.frames;
    if (projectToImage(camera, pos, k.yaw, centre, 8.0) &&
        validity.world().occluders().clear(cameraPosition(camera, pos, k.yaw), centre, {})) {
      ++r.seen;
    }
  };
  r.path.push_back(keyframe(t0));
  Vec3 c = chasePoint(t0);
  judge(r.path.back(), c);
  const int steps = static_cast<int>(std::floor((t_end - t0) / chase.step + 1e-9));
  for (int i = 0; i < steps; ++i) {
    const double t = t0 + i * chase.step, tn = t0 + (i + 1) * chase.step;
    const Vec3 cn = chasePoint(tn);  // (c: the chase point at t, carried from the last step)
    // Feed-forward of the chase point's motion plus a pull towards it, then the limits.
    Vec3 want = (cn - c) / chase.step + (c - q) / chase.time_constant;
    want = clampNorm2(want, sp.max_speed - 0.01);  // (keyframes are rounded to the millimetre)
    want.z() = std::clamp(want.z(), -sp.descent_rate, sp.climb_rate);
    Vec3 dv = want - v;
    dv = clampNorm2(dv, sp.accel * chase.step);
    v += dv;
    v.z() = want.z();
    Vec3 next = q + v * chase.step;
    next.z() = std::clamp(next.z(), zmin, zmax);
    // At the edge of the area the UAV waits for a target that drives out of it.
    const geometry::Aabb2& b = validity.bounds();
    next.x() = std::clamp(next.x(), b.min.x() + kEdge, b.max.x() - kEdge);
    next.y() = std::clamp(next.y(), b.min.y() + kEdge, b.max.y() - kEdge);
    for (int a = 0; a < 3; ++a) next[a] = scenario::roundMilli(next[a]);
    auto valid = [&](const Vec3& to) {
      return validity.staticSegmentValid(q, to) && validity.kozSegmentClear(q, to, t, tn);
    };
    // A step into an obstacle or a keep-out zone: hold where it is, if that is safe.
    if (!valid(next)) next = q;
    if (!valid(next)) {
      char buf[160];
      std::snprintf(buf, sizeof(buf),
                    "t = %.1f s: the chase from (%.1f, %.1f, %.1f) meets an obstacle, the band's "
                    "or the area's bounds or a keep-out zone",
                    t, q.x(), q.y(), q.z());
      r.message = buf;
      return r;
    }
    v = (next - q) / chase.step;
    q = next;
    r.path.push_back(keyframe(tn));
    judge(r.path.back(), cn);
    c = cn;
  }
  r.status = PlanStatus::kExact;
  return r;
}

}  // namespace hameritt::planning
