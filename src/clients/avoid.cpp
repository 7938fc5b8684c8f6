#include "hameritt/clients/avoid.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hameritt/generation/avoid.h"
#include "hameritt/scenario/error.h"

namespace hameritt::clients {

using geometry::Vec2;
using geometry::Vec3;

namespace {

void requireIn(const char* field, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi)) {
    throw scenario::ConfigError(std::string("avoid.") + field + ": expected [" +
                                std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                                std::to_string(v));
  }
}

const scenario::AvoidPhaseSpec& avoidPhase(const scenario::Mission& m) {
  for (const auto& p : m.phases) {
    if (p.type == scenario::PhaseType::kAvoid) return p.avoid;
  }
  throw scenario::ConfigError("mission " + m.scenario_id + ": phases: no avoid phase to fly");
}

std::vector<scenario::KeepOutZone> zones(const scenario::Mission& m, bool moving) {
  std::vector<scenario::KeepOutZone> out;
  for (const auto& k : m.kozs) {
    if (k.motion.empty() != moving) out.push_back(k);
  }
  return out;
}

// The speeds tried, as fractions of the cruise speed, fastest first; and the offsets (m).
constexpr double kSpeeds[] = {1.0, 0.7, 0.45, 0.2, 0.0, -0.5};
constexpr double kOffsets[] = {0.0, 6.0, -6.0, 12.0, -12.0, 18.0};
// Metres before the goal over which the vertical offset fades out.
constexpr double kTaper = 20.0;
// Metres kept from the static obstacles when planning (the generator's shortest path keeps 1).
constexpr double kClearance = 2.5;
// A turn sharper than this (rad) is a corner, taken at no more than kCornerSpeed (m/s) from
// kCornerSlowdown metres before it until the reference has passed it.
constexpr double kCornerAngle = 0.35;
constexpr double kCornerSpeed = 3.0;
constexpr double kCornerSlowdown = 10.0;
// Seconds held before the path is planned again, and how many times.
constexpr double kStallReplan = 8.0;
constexpr int kMaxReplans = 3;

}  // namespace

void AvoidSettings::validate() const {
  requireIn("horizon", horizon, 1.0, 60.0);
  requireIn("step", step, 0.05, 2.0);
  requireIn("horizontal_buffer", horizontal_buffer, 0.0, 100.0);
  requireIn("vertical_buffer", vertical_buffer, 0.0, 100.0);
  requireIn("speed_fraction", speed_fraction, 0.05, 1.0);
  requireIn("climb_rate", climb_rate, 0.1, 20.0);
  requireIn("koz_margin", koz_margin, 0.0, 50.0);
  requireIn("lead", lead, 0.0, 5.0);
  requireIn("max_lag", max_lag, 1.0, 100.0);
  requireIn("stale_after", stale_after, 0.1, 60.0);
}

AvoidPilot::AvoidPilot(const scenario::World& world, const scenario::Mission& mission,
                       const scenario::UavSpec& uav, const AvoidSettings& settings)
    : world_(world),
      spec_(avoidPhase(mission)),
      uav_(uav),
      settings_(settings),
      static_kozs_(zones(mission, false)),
      moving_kozs_(zones(mission, true)),
      band_(world, static_kozs_, planning::validitySettingsFor(uav, kClearance)),
      tight_(world, static_kozs_, planning::validitySettingsFor(uav)) {
  settings_.validate();
}

bool AvoidPilot::plan(const Vec3& start, std::optional<double> freeze_at) {
  path_.clear();
  cumulative_.clear();
  // Planned with kClearance from the obstacles (the autopilot cuts corners); where that finds
  // no flight (a narrow gap), with the generator's 1 m.
  scenario::ReferenceFlight f;
  if (freeze_at && !moving_kozs_.empty()) {
    // A replan after a stall: the moving zones where they are now, as static ones.
    std::vector<scenario::KeepOutZone> zones = static_kozs_;
    for (const auto& k : moving_kozs_) {
      scenario::KeepOutZone z = k;
      z.polygon = scenario::kozPolygonAt(k, *freeze_at);
      z.motion.clear();
      zones.push_back(z);
    }
    // Kept farther from the frozen zones than the stall margin (else the new path stalls
    // too), then with less where that finds nothing.
    for (double margin : {settings_.koz_margin + 0.5, kClearance, 1.0}) {
      f = scenario::shortestFlight(
          planning::WorldValidity(world_, zones, planning::validitySettingsFor(uav_, margin)),
          start, spec_.goal);
      if (f.ok) break;
    }
  } else {
    f = scenario::shortestFlight(band_, start, spec_.goal);
    if (!f.ok) f = scenario::shortestFlight(tight_, start, spec_.goal);
  }
  if (!f.ok) {
    why_ = f.why;
    return false;
  }
  path_ = f.path;
  cumulative_.assign(path_.size(), 0.0);
  for (std::size_t i = 1; i < path_.size(); ++i) {
    cumulative_[i] = cumulative_[i - 1] + (path_[i] - path_[i - 1]).norm();
  }
  // Corners: where the path turns by more than kCornerAngle.
  corners_.clear();
  for (std::size_t i = 1; i + 1 < path_.size(); ++i) {
    const Vec3 a = path_[i] - path_[i - 1], b = path_[i + 1] - path_[i];
    if (a.norm() < 1e-6 || b.norm() < 1e-6) continue;
    const double c = std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0);
    if (std::acos(c) > kCornerAngle) corners_.push_back(cumulative_[i]);
  }
  s_ = 0.0;
  offset_ = 0.0;
  started_ = false;
  why_.clear();
  return true;
}

void AvoidPilot::observe(const TrafficReport& report) {
  if (!std::isfinite(report.t) || !report.position.allFinite() || !report.velocity.allFinite()) {
    return;
  }
  auto it = traffic_.find(report.id);
  if (it != traffic_.end() && it->second.t > report.t) return;
  traffic_[report.id] = report;
}

Vec3 AvoidPilot::pointAt(double s, double offset) const {
  if (path_.empty()) return Vec3(0, 0, 0);
  s = std::clamp(s, 0.0, cumulative_.back());
  std::size_t i = 1;
  while (i + 1 < path_.size() && cumulative_[i] < s) ++i;
  const double len = cumulative_[i] - cumulative_[i - 1];
  const double u = len > 1e-9 ? (s - cumulative_[i - 1]) / len : 1.0;
  Vec3 p = path_[i - 1] + (path_[i] - path_[i - 1]) * u;
  // The offset applies in the flight band only (not on the take-off and landing columns),
  // and keeps a metre and a half inside it.
  // It fades out over the last kTaper metres, so that the path ends at the goal.
  const double lo = uav_.altitude_min, hi = uav_.altitude_max;
  offset *= std::clamp((cumulative_.back() - s) / kTaper, 0.0, 1.0);
  if (offset != 0.0 && p.z() >= lo - 0.5) {
    p.z() = std::clamp(p.z() + offset, lo + 1.5, hi - 1.5);
  }
  return p;
}

double AvoidPilot::project(const Vec3& p, double from) const {
  // The nearest point of the path to p at or after arc length `from` - 20 m (the UAV never
  // jumps ahead far; searching from near the reference avoids a path that doubles back).
  double best = from, best_d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < path_.size(); ++i) {
    if (cumulative_[i] < from - 20.0) continue;
    const Vec3 a = path_[i - 1], b = path_[i];
    const Vec3 ab = b - a;
    const double l2 = ab.squaredNorm();
    const double u = l2 > 1e-12 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
    const double d = (a + ab * u - p).norm();
    if (d < best_d) {
      best_d = d;
      best = cumulative_[i - 1] + u * std::sqrt(l2);
    }
  }
  return best;
}

double AvoidPilot::separation(const Vec3& p, double t) const {
  double sep = std::numeric_limits<double>::infinity();
  for (const auto& [id, r] : traffic_) {
    const Vec3 q = r.position + r.velocity * (t - r.t);
    const double h = (p - q).head<2>().norm() / std::max(1e-6, settings_.horizontal_buffer);
    const double v = std::abs(p.z() - q.z()) / std::max(1e-6, settings_.vertical_buffer);
    sep = std::min(sep, std::max(h, v));
  }
  for (const auto& k : moving_kozs_) {
    if (!k.window.active(t)) continue;
    const bool in_band = (!k.alt_min || p.z() >= *k.alt_min - settings_.koz_margin) &&
                         (!k.alt_max || p.z() <= *k.alt_max + settings_.koz_margin);
    if (!in_band) continue;
    const geometry::Polygon poly = scenario::kozPolygonAt(k, t);
    const Vec2 q = p.head<2>();
    const double d = poly.contains(q) ? 0.0 : poly.distance(q);
    sep = std::min(sep, d / std::max(1e-6, settings_.koz_margin));
  }
  return sep;
}

AvoidPilot::Candidate AvoidPilot::evaluate(double t, double speed, double offset) const {
  Candidate c;
  c.speed = speed;
  c.offset = offset;
  c.first_conflict = settings_.horizon;
  c.closest = std::numeric_limits<double>::infinity();
  const double len = cumulative_.back();
  for (double tau = settings_.step; tau <= settings_.horizon + 1e-9; tau += settings_.step) {
    const double s = std::clamp(s_ + speed * tau, 0.0, len);
    // The offset moves from the current one at the climb rate.
    const double dz = offset - offset_;
    const double moved = std::min(std::abs(dz), settings_.climb_rate * tau);
    const double off = offset_ + std::copysign(moved, dz);
    const Vec3 p = pointAt(s, off);
    if (offset != 0.0 && tau <= 2.0 * settings_.step + 1e-9 && !band_.staticValid(p)) {
      c.valid = false;
    }
    const double sep = separation(p, t + tau);
    if (sep < c.closest) c.closest = sep;
    if (sep < 1.0 && c.first_conflict >= settings_.horizon) c.first_conflict = tau;
  }
  return c;
}

AvoidCommand AvoidPilot::step(double t, const Vec3& uav) {
  AvoidCommand cmd;
  if (path_.empty()) {
    cmd.setpoint = uav;
    cmd.reason = "no path";
    return cmd;
  }
  const double dt = started_ ? std::clamp(t - last_t_, 0.0, 1.0) : 0.0;
  started_ = true;
  last_t_ = t;
  for (auto it = traffic_.begin(); it != traffic_.end();) {
    it = t - it->second.t > settings_.stale_after ? traffic_.erase(it) : std::next(it);
  }

  double cruise = settings_.speed_fraction * uav_.max_speed;
  for (double c : corners_) {
    if (s_ > c - kCornerSlowdown && s_ < c + 1.0) cruise = std::min(cruise, kCornerSpeed);
  }
  const double len = cumulative_.back();
  // The candidate moves in the order of preference; the first that keeps the buffer wins.
  std::optional<Candidate> best, fallback;
  for (double f : kSpeeds) {
    for (double off : kOffsets) {
      const Candidate c = evaluate(t, f * cruise, off);
      if (!c.valid) continue;
      if (c.first_conflict >= settings_.horizon) {
        const auto better = [&](const Candidate& a, const Candidate& b) {
          if (a.speed != b.speed) return a.speed > b.speed;
          if (std::abs(a.offset) != std::abs(b.offset)) {
            return std::abs(a.offset) < std::abs(b.offset);
          }
          return std::abs(a.offset - offset_) < std::abs(b.offset - offset_);
        };
        if (!best || better(c, *best)) best = c;
      } else if (!fallback || c.first_conflict > fallback->first_conflict ||
                 (c.first_conflict == fallback->first_conflict && c.closest > fallback->closest)) {
        fallback = c;
      }
    }
    if (best) break;  // a slower candidate is never preferred to a faster one that keeps it
  }
  const Candidate chosen = best ? *best : fallback ? *fallback : Candidate{};
  // Held (or backing off) for kStallReplan s: a zone or an aircraft sits on the path. The path
  // is planned again from here, around the moving zones where they are now (at most
  // kMaxReplans times); this tick holds.
  if (chosen.speed > 0.0 || s_ >= len - 1e-6) {
    stalled_since_.reset();
  } else if (!stalled_since_) {
    stalled_since_ = t;
  } else if (t - *stalled_since_ >= kStallReplan && replans_ < kMaxReplans) {
    const std::vector<Vec3> old_path = path_;
    const std::vector<double> old_cumulative = cumulative_, old_corners = corners_;
    const double old_s = s_, old_offset = offset_;
    ++replans_;
    stalled_since_.reset();
    if (plan(uav, t)) {
      cmd.setpoint = uav;
      cmd.reason = "stalled: planned again around the moving zones";
      last_t_ = t;
      started_ = true;
      return cmd;
    }
    path_ = old_path;  // no other way: keep waiting on the old one
    cumulative_ = old_cumulative;
    corners_ = old_corners;
    s_ = old_s;
    offset_ = old_offset;
  }
  cmd.conflict = !best;
  cmd.speed = chosen.speed;
  // The reference advances (or backs off) at the chosen speed, but waits for a lagging UAV.
  const double along = project(uav, s_);
  double next = std::clamp(s_ + chosen.speed * dt, 0.0, len);
  if (chosen.speed > 0.0 && (pointAt(s_, offset_) - uav).norm() > settings_.max_lag) {
    next = std::max(s_, std::min(next, along + settings_.max_lag));
  }
  s_ = next;
  const double dz = chosen.offset - offset_;
  offset_ += std::copysign(std::min(std::abs(dz), settings_.climb_rate * dt), dz);
  cmd.offset = offset_;
  cmd.at_goal = s_ >= len - 1e-6;
  cmd.setpoint = pointAt(std::clamp(s_ + chosen.speed * settings_.lead, 0.0, len), offset_);
  // Facing along the path (towards the goal on the take-off and landing columns).
  Vec3 ahead = pointAt(std::min(len, s_ + 5.0)) - pointAt(s_);
  if (ahead.head<2>().norm() < 0.5) ahead = spec_.goal - uav;
  cmd.yaw = ahead.head<2>().norm() > 0.5 ? std::atan2(ahead.y(), ahead.x()) : 0.0;
  char buf[160];
  std::snprintf(buf, sizeof(buf), "%s: %.1f m/s, offset %+.0f m, closest %.2f of the buffer",
                best ? "clear" : "conflict", chosen.speed, chosen.offset,
                std::isfinite(chosen.closest) ? chosen.closest : 99.0);
  cmd.reason = buf;
  return cmd;
}

}  // namespace hameritt::clients
