#include "hameritt/planning/look_at.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <limits>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/rng.h"

namespace hameritt::planning {

using geometry::Vec2;
using geometry::Vec3;

namespace {

Eigen::Matrix3d worldFromCamera(const scenario::CameraSpec& cam, double uav_yaw) {
  const Vec3 rpy = cam.mount_rpy * (geometry::kPi / 180.0);
  // Positive pitch about +y (left) turns the forward axis down.
  return (Eigen::AngleAxisd(uav_yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(rpy.z(), Vec3::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Vec3::UnitY()) * Eigen::AngleAxisd(rpy.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

bool sees(const WorldValidity& v, const scenario::CameraSpec& cam, const Vec3& pos, double yaw,
          const LookAtTarget& t, double margin, Vec2* px) {
  const auto p = projectToImage(cam, pos, yaw, t.point, margin);
  if (!p) return false;
  if (!v.world().occluders().clear(cameraPosition(cam, pos, yaw), t.point, t.own_occluders)) {
    return false;
  }
  *px = *p;
  return true;
}

}  // namespace

Vec3 cameraPosition(const scenario::CameraSpec& cam, const Vec3& uav_position, double uav_yaw) {
  return uav_position + Eigen::AngleAxisd(uav_yaw, Vec3::UnitZ()) * cam.mount_xyz;
}

std::optional<Vec2> projectToImage(const scenario::CameraSpec& cam, const Vec3& uav_position,
                                   double uav_yaw, const Vec3& point, double margin_px) {
  const Vec3 c = worldFromCamera(cam, uav_yaw).transpose() *
                 (point - cameraPosition(cam, uav_position, uav_yaw));
  if (c.x() <= 1e-6) return std::nullopt;  // behind the camera (x forward, y left, z up)
  const double f = 0.5 * cam.width / std::tan(0.5 * cam.hfov_deg * geometry::kPi / 180.0);
  const double u = 0.5 * cam.width - f * c.y() / c.x();
  const double w = 0.5 * cam.height - f * c.z() / c.x();
  if (u < margin_px || u > cam.width - margin_px || w < margin_px || w > cam.height - margin_px) {
    return std::nullopt;
  }
  return Vec2(u, w);
}

void LookAtSettings::validate() const {
  auto need = [](bool ok, const char* f, const std::string& what, double v) {
    if (!ok)
      throw scenario::ConfigError(std::string("look_at.") + f + ": expected " + what + ", got " +
                                  scenario::formatNumber(v));
  };
  need(candidates >= 1, "candidates", "an integer >= 1", candidates);
  need(range_min >= 0, "range_min", "metres >= 0", range_min);
  need(range_max > range_min, "range_max", "metres > range_min", range_max);
  need(margin_px >= 0, "margin_px", "pixels >= 0", margin_px);
  need(dwell > 0, "dwell", "seconds > 0", dwell);
  need(yaw_rate_deg > 0, "yaw_rate_deg", "degrees per second > 0", yaw_rate_deg);
}

LookAtResult planLookAtPath(const WorldValidity& validity, const scenario::CameraSpec& camera,
                            const Vec3& start, double t0, const std::vector<LookAtTarget>& targets,
                            const UavPlannerSettings& settings, std::uint64_t seed,
                            const LookAtSettings& look) {
  look.validate();
  settings.validate();
  LookAtResult r;
  const auto& vs = validity.settings();
  const double pitch = camera.mount_rpy.y() * geometry::kPi / 180.0;
  constexpr double kForever = std::numeric_limits<double>::infinity();
  // 1. A viewpoint per target.
  struct Pick {
    std::size_t target;
    Vec3 pos;
    double yaw;
  };
  std::vector<Pick> picks;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const LookAtTarget& t = targets[i];
    scenario::Rng rng(scenario::deriveSeed(seed, i));
    bool found = false;
    for (int k = 0; k < look.candidates && !found; ++k) {
      const double psi = rng.uniform(-geometry::kPi, geometry::kPi);
      const double z = rng.uniform(vs.altitude_min, vs.altitude_max);
      double d;
      if (pitch > geometry::degToRad(2.0) && pitch < geometry::degToRad(88.0)) {
        d = (z - t.point.z()) / std::tan(pitch) * rng.uniform(0.8, 1.25);
      } else if (pitch >= geometry::degToRad(88.0)) {
        d = rng.uniform(0.0, 0.3 * (z - t.point.z()));
      } else {
        d = rng.uniform(look.range_min, look.range_max);
      }
      if (!(d >= 0)) continue;
      const Vec2 dir(std::cos(psi), std::sin(psi));
      const Vec2 xy = t.point.head<2>() - dir * d;
      const Vec3 pos(xy.x(), xy.y(), z);
      if (!validity.staticValid(pos) || !validity.kozClear(pos, t0, kForever)) continue;
      Vec2 px;
      if (!sees(validity, camera, pos, psi, t, look.margin_px, &px)) continue;
      picks.push_back({i, pos, psi});
      found = true;
    }
    if (!found) r.unseen.push_back(t.id);
  }
  // 2. Greedy nearest-neighbour order from the start.
  std::vector<Pick> order;
  Vec3 at = start;
  while (!picks.empty()) {
    std::size_t best = 0;
    for (std::size_t j = 1; j < picks.size(); ++j) {
      if ((picks[j].pos - at).norm() < (picks[best].pos - at).norm()) best = j;
    }
    order.push_back(picks[best]);
    at = picks[best].pos;
    picks.erase(picks.begin() + static_cast<long>(best));
  }
  // 3. Fly legs; turn in place and dwell at each viewpoint.
  PlanResult& f = r.flight;
  f.status = PlanStatus::kExact;
  double t = t0;
  Vec3 from = start;
  using scenario::roundMilli;
  // Each viewpoint's arrival, turn and dwell samples; whether each leg starts where the path
  // before it ends (see 4).
  std::vector<scenario::Trajectory> stops;
  bool legsJoin = true;
  for (std::size_t j = 0; j < order.size(); ++j) {
    const PlanResult leg = planUavPath(validity, from, order[j].pos, t, settings,
                                       scenario::deriveSeed(seed, 1000 + j));
    f.iterations += leg.iterations;
    f.planning_time += leg.planning_time;
    if (leg.status != PlanStatus::kExact) {
      r.status = leg.status;
      r.message = "leg to the viewpoint of " + targets[order[j].target].id + ": " + leg.message;
      f.status = leg.status;
      f.path.clear();
      return r;
    }
    if (!f.path.empty()) {
      const auto &end = f.path.back(), &first = leg.path.front();
      legsJoin = legsJoin && first.t == end.t && first.x == end.x && first.y == end.y &&
                 first.z == end.z;
    }
    for (std::size_t k = f.path.empty() ? 0 : 1; k < leg.path.size(); ++k)
      f.path.push_back(leg.path[k]);
    f.length += leg.length;
    auto last = f.path.back();
    const double turn = std::abs(geometry::wrapPi(order[j].yaw - last.yaw));
    last.t = roundMilli(last.t + std::max(0.1, geometry::radToDeg(turn) / look.yaw_rate_deg));
    last.yaw = roundMilli(order[j].yaw);
    f.path.push_back(last);
    last.t = roundMilli(last.t + look.dwell);
    f.path.push_back(last);
    stops.emplace_back(f.path.end() - 3, f.path.end());
    t = last.t;
    from = Vec3(last.x, last.y, last.z);
  }
  if (f.path.empty())
    f.path.push_back(
        {roundMilli(t0), roundMilli(start.x()), roundMilli(start.y()), roundMilli(start.z()), 0.0});
  // 4. Verify on the final path: whole path valid; each dwell sample sees its target.
  // planUavPath checked each leg's segments with the same test and slack (checkTrajectory is
  // exact per segment and depends on the samples' positions and times only), so where every
  // leg starts at the sample before it the turns and dwells are the only segments left; a
  // failure there (or a leg that does not join) re-checks the whole path for its message.
  bool stopsValid = legsJoin && !stops.empty();
  for (std::size_t j = 0; j < stops.size() && stopsValid; ++j)
    stopsValid = validity.checkTrajectory(stops[j], 0.25, 2e-3).empty();
  const std::string err = stopsValid ? std::string() : validity.checkTrajectory(f.path, 0.25, 2e-3);
  if (!err.empty()) {
    r.status = f.status = PlanStatus::kNoSolution;
    r.message = "final path rejected: " + err;
    return r;
  }
  std::size_t dwell = 0;
  for (std::size_t j = 0; j < order.size(); ++j) {
    // The j-th turn-in-place pair: two samples at one position with the viewing yaw.
    for (; dwell + 1 < f.path.size(); ++dwell) {
      const auto& a = f.path[dwell];
      const auto& b = f.path[dwell + 1];
      if (a.x == b.x && a.y == b.y && a.z == b.z && a.yaw == b.yaw &&
          a.yaw == roundMilli(order[j].yaw)) {
        break;
      }
    }
    if (dwell + 1 >= f.path.size()) {
      r.status = PlanStatus::kNoSolution;
      r.message = "viewpoint of " + targets[order[j].target].id + " missing from the path";
      return r;
    }
    const auto& s = f.path[dwell];
    const Vec3 pos(s.x, s.y, s.z);
    Vec2 px;
    if (!sees(validity, camera, pos, s.yaw, targets[order[j].target], 0.0, &px)) {
      r.status = PlanStatus::kNoSolution;
      r.message = "target " + targets[order[j].target].id + " not visible from its viewpoint";
      return r;
    }
    r.viewpoints.push_back({targets[order[j].target].id, pos, s.yaw, s.t, px});
    dwell += 2;
  }
  if (!r.unseen.empty()) {
    r.status = PlanStatus::kNoSolution;
    r.message = "no viewpoint for " + std::to_string(r.unseen.size()) + " target(s), first " +
                r.unseen.front();
  } else {
    r.status = PlanStatus::kExact;
    r.message = "every target verified in view";
  }
  return r;
}

}  // namespace hameritt::planning
