#include "hameritt/clients/pursuit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "hameritt/clients/color_detector.h"
#include "hameritt/geometry/segment.h"
#include "hameritt/planning/look_at.h"
#include "hameritt/scenario/error.h"

namespace hameritt::clients {

using geometry::Vec2;
using geometry::Vec3;

namespace {

constexpr double kBodyHeight = 0.8;  // m: the point looked at, above the vehicle's ground point

void requirePositive(double v, const char* field, bool allow_zero = false) {
  if (!std::isfinite(v) || v < 0.0 || (!allow_zero && v == 0.0)) {
    throw scenario::ConfigError(std::string("pursuit.") + field + ": expected a " +
                                (allow_zero ? "non-negative" : "positive") +
                                " finite number, got " + scenario::formatNumber(v));
  }
}

}  // namespace

void PursuitSettings::validate() const {
  requirePositive(standoff, "standoff", true);
  requirePositive(height, "height");
  requirePositive(lead, "lead", true);
  requirePositive(predict_horizon, "predict_horizon", true);
  requirePositive(clearance, "clearance", true);
  requirePositive(margin_px, "margin_px", true);
  requirePositive(speed_window, "speed_window");
  requirePositive(envelope_radius, "envelope_radius", true);
  requirePositive(envelope_height, "envelope_height", true);
}

StreetPredictor::StreetPredictor(const scenario::World& world, const PursuitSettings& settings)
    : world_(world), settings_(settings) {
  settings_.validate();
}

bool StreetPredictor::observe(double t, const Vec3& position, double yaw) {
  if (!std::isfinite(t) || !position.allFinite() || !std::isfinite(yaw)) return false;
  if (!recent_.empty() && !(t > recent_.back().t)) return false;
  VehicleState s;
  s.t = t;
  s.position = position;
  s.yaw = yaw;
  recent_.push_back(s);
  while (recent_.size() > 2 && recent_.front().t < t - settings_.speed_window) recent_.pop_front();
  // Speed along the heading over the window (a sighting older than the window, after a gap,
  // still gives a speed: the mean over the gap).
  const VehicleState& first = recent_.front();
  const double dt = t - first.t;
  if (recent_.size() >= 2 && dt > 0.05) {
    const Vec2 d = (position - first.position).head<2>();
    s.speed = std::max(0.0, d.dot(Vec2(std::cos(yaw), std::sin(yaw)))) / dt;
  } else if (recent_.size() >= 2) {
    s.speed = last_.speed;
  }
  recent_.back().speed = s.speed;
  last_ = s;
  return true;
}

bool StreetPredictor::observe(double t, const Vec3& position, double yaw, double speed) {
  if (!std::isfinite(speed) || speed < 0.0) return false;
  if (!observe(t, position, yaw)) return false;
  recent_.back().speed = speed;
  last_.speed = speed;
  return true;
}

bool StreetPredictor::observe(double t, const Vec3& position) {
  double yaw = last_.yaw;
  if (!recent_.empty()) {
    const Vec2 d = (position - last_.position).head<2>();
    if (d.norm() > 2.0) yaw = std::atan2(d.y(), d.x());
  }
  return observe(t, position, yaw);
}

VehicleState StreetPredictor::predict(double t) const {
  return walk(t, Branches::kStraight).front();
}

std::vector<VehicleState> StreetPredictor::hypotheses(double t) const {
  return walk(t, Branches::kEvery);
}

VehicleState StreetPredictor::predictToJunction(double t) const {
  return walk(t, Branches::kStopAtJunction).front();
}

std::vector<VehicleState> StreetPredictor::walk(double t, Branches branches) const {
  VehicleState start = last_;
  start.t = t;
  const double dt = std::clamp(t - last_.t, 0.0, settings_.predict_horizon);
  const double distance = last_.speed * dt;
  if (!(distance > 1e-6) || world_.edges().empty()) return {start};
  // The street the vehicle drives on: the nearest centreline, driven the way it heads.
  const Vec2 p = last_.position.head<2>();
  const Vec2 heading(std::cos(last_.yaw), std::sin(last_.yaw));
  int edge = -1;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < world_.edges().size(); ++i) {
    const auto& e = world_.edges()[i];
    const double d = geometry::pointSegmentDistance(p, world_.nodes()[e.a].position,
                                                    world_.nodes()[e.b].position);
    if (d < best) best = d, edge = static_cast<int>(i);
  }
  const auto& e0 = world_.edges()[static_cast<std::size_t>(edge)];
  const Vec2 a0 = world_.nodes()[e0.a].position, b0 = world_.nodes()[e0.b].position;
  const bool forward = (b0 - a0).dot(heading) >= 0.0;
  // Walk from the projection, keeping the lateral offset (the lane).
  const Vec2 along0 = geometry::closestPointOnSegment(p, a0, b0);
  const Vec2 dir0 = ((forward ? b0 : a0) - (forward ? a0 : b0)).normalized();
  const double lateral = (p - along0).dot(Vec2(dir0.y(), -dir0.x()));
  struct Walker {
    Vec2 along, dir;
    int to;
    double left;
  };
  std::vector<Walker> open{{along0, dir0, forward ? e0.b : e0.a, distance}};
  std::vector<VehicleState> ends;
  auto finish = [&](const Vec2& along, const Vec2& dir) {
    VehicleState out = start;
    const Vec2 q = along + Vec2(dir.y(), -dir.x()) * lateral;
    out.position = Vec3(q.x(), q.y(), last_.position.z());
    out.yaw = std::atan2(dir.y(), dir.x());
    ends.push_back(out);
  };
  constexpr std::size_t kMaxHypotheses = 64;
  for (int steps = 0; !open.empty() && steps < 4096; ++steps) {
    Walker w = open.back();
    open.pop_back();
    const Vec2 node = world_.nodes()[static_cast<std::size_t>(w.to)].position;
    const double span = (node - w.along).norm();
    if (w.left <= span) {
      finish(w.along + w.dir * w.left, w.dir);
      continue;
    }
    // The leaving edges, never back the way it came; straight on (the smallest turn) first.
    std::vector<std::pair<double, int>> next;
    for (int ei : world_.adjacency()[static_cast<std::size_t>(w.to)]) {
      const auto& e = world_.edges()[static_cast<std::size_t>(ei)];
      const int other = e.a == w.to ? e.b : e.a;
      const Vec2 d = world_.nodes()[static_cast<std::size_t>(other)].position - node;
      if (d.norm() < 1e-9) continue;
      const double c = d.normalized().dot(w.dir);
      if (c < -0.99) continue;
      next.emplace_back(-c, other);
    }
    std::sort(next.begin(), next.end());
    if (next.empty() || (branches == Branches::kStopAtJunction && next.size() > 1)) {
      finish(node, w.dir);  // a dead end, or a choice ahead: it is there or beyond
      continue;
    }
    const std::size_t take = branches == Branches::kEvery ? next.size() : 1;
    for (std::size_t k = take; k-- > 0;) {  // pushed last = straight on, walked first
      if (ends.size() + open.size() >= kMaxHypotheses) break;
      const Vec2 to = world_.nodes()[static_cast<std::size_t>(next[k].second)].position;
      open.push_back({node, (to - node).normalized(), next[k].second, w.left - span});
    }
  }
  if (ends.empty()) ends.push_back(start);
  return ends;
}

GroupView groupView(const std::vector<VehicleState>& vehicles, const scenario::CameraSpec& camera,
                    double margin) {
  GroupView g;
  if (vehicles.empty()) return g;
  g.centre = vehicles.front();
  if (vehicles.size() == 1) return g;
  // The two farthest apart set the line; the midpoint of the extremes is the centre.
  std::size_t a = 0, b = 1;
  double span = -1.0;
  for (std::size_t i = 0; i < vehicles.size(); ++i) {
    for (std::size_t j = i + 1; j < vehicles.size(); ++j) {
      const double d = (vehicles[i].position - vehicles[j].position).head<2>().norm();
      if (d > span) span = d, a = i, b = j;
    }
  }
  g.centre.position = 0.5 * (vehicles[a].position + vehicles[b].position);
  Vec2 d = (vehicles[b].position - vehicles[a].position).head<2>();
  // Across the line, to the left of the first vehicle's heading (so that the yaw does not flip).
  const double h = vehicles.front().yaw;
  if (d.dot(Vec2(std::cos(h), std::sin(h))) < 0.0) d = -d;
  const double yaw = std::atan2(d.y(), d.x()) + 0.5 * geometry::kPi;
  g.centre.yaw = std::atan2(std::sin(yaw), std::cos(yaw));
  // Half the span and the margin within half the image's width, the optical axis straight down.
  const double half = std::tan(0.5 * camera.hfov_deg * geometry::kPi / 180.0);
  g.height = (0.5 * span + margin) / std::max(half, 1e-6);
  return g;
}

double levelReach(const scenario::CameraSpec& camera, double height) {
  const double th = std::tan(0.5 * camera.hfov_deg * geometry::kPi / 180.0);
  // The vertical half-angle's tangent from the horizontal one and the aspect (square pixels).
  const double tv = th * camera.height / std::max(1, camera.width);
  return std::max(0.0, height) * std::hypot(th, tv);
}

geometry::Vec2 tiltedAxisShift(const scenario::CameraSpec& camera,
                               const Eigen::Quaterniond& attitude, double height) {
  // The optical axis (the optical frame's z) with the UAV's attitude, and with the same
  // heading, level.
  const auto axis = [&](const Eigen::Quaterniond& q) -> Vec3 {
    return opticalPose(Eigen::Isometry3d(q), Vec3::Zero(), camera.mount_rpy).linear().col(2);
  };
  const Vec3 fwd = attitude * Vec3::UnitX();
  const Vec3 tilted = axis(attitude);
  const Vec3 level =
      axis(Eigen::Quaterniond(Eigen::AngleAxisd(std::atan2(fwd.y(), fwd.x()), Vec3::UnitZ())));
  const double min_down = std::sin(10.0 * geometry::kPi / 180.0);
  if (-tilted.z() < min_down || -level.z() < min_down || height <= 0.0) return Vec2::Zero();
  const Vec2 hit_tilted = tilted.head<2>() * (height / -tilted.z());
  const Vec2 hit_level = level.head<2>() * (height / -level.z());
  return hit_tilted - hit_level;
}

TiltAverage::TiltAverage(double rate, double station_radius, double steady_speed)
    : rate_(rate), station_radius_(station_radius), steady_speed_(steady_speed) {}

const Vec2& TiltAverage::update(const Vec2& uav, const Vec2& uav_velocity, const Vec2& station,
                                const Vec2& vehicle_velocity, const Vec2& measured) {
  if ((uav - station).norm() < station_radius_ &&
      (uav_velocity - vehicle_velocity).norm() < steady_speed_) {
    shift_ += rate_ * (measured - shift_);
  }
  return shift_;
}

ViewpointChooser::ViewpointChooser(const scenario::World& world, const scenario::UavSpec& uav,
                                   const std::vector<scenario::KeepOutZone>& kozs,
                                   const PursuitSettings& settings)
    : world_(world), uav_(uav), kozs_(kozs), settings_(settings) {
  settings_.validate();
}

namespace {

// The altitudes a viewpoint may take: the band, 1.5 m inside each end (its floor when the band
// is narrower than 3 m).
std::pair<double, double> viewBand(const scenario::UavSpec& uav) {
  const double lo = uav.altitude_min + 1.5;
  return {lo, std::max(lo, uav.altitude_max - 1.5)};
}

}  // namespace

double ViewpointChooser::safeAltitude(const Vec2& p, double wanted) const {
  const auto [lo, hi] = viewBand(uav_);
  double z = std::clamp(wanted, lo, hi);
  const auto& occ = world_.occluders();
  for (int i : occ.near(p, 6.0)) z = std::max(z, occ.box(i).maxZ() + settings_.clearance);
  return z;
}

bool ViewpointChooser::usable(const Vec3& p, double t) const {
  // Above the band: the roof of a tower beside the vehicle lifted it there (safeAltitude).
  return p.z() <= viewBand(uav_).second + 1e-9 && !inKoz(p, t);
}

bool ViewpointChooser::inKoz(const Vec3& p, double t) const {
  for (const auto& k : kozs_) {
    if (!k.window.active(t)) continue;
    if ((k.alt_min && p.z() < *k.alt_min) || (k.alt_max && p.z() > *k.alt_max)) continue;
    if (k.polygon.contains(p.head<2>())) return true;
  }
  return false;
}

bool ViewpointChooser::kozClear(const Vec3& a, const Vec3& b, double t) const {
  const double z0 = std::min(a.z(), b.z()), z1 = std::max(a.z(), b.z());
  for (const auto& k : kozs_) {
    if (!k.window.active(t)) continue;
    if ((k.alt_min && z1 < *k.alt_min) || (k.alt_max && z0 > *k.alt_max)) continue;
    if (k.polygon.intersectsSegment(a.head<2>(), b.head<2>())) return false;
  }
  return true;
}

std::optional<std::string> ViewpointChooser::seenBy(const Vec3& position, double yaw,
                                                    const Vec3& target) const {
  for (const auto& cam : uav_.cameras) {
    if (!settings_.camera.empty() && cam.name != settings_.camera) continue;
    if (!planning::projectToImage(cam, position, yaw, target, settings_.margin_px)) continue;
    const Vec3 c = planning::cameraPosition(cam, position, yaw);
    if (world_.occluders().clear(c, target)) return cam.name;
  }
  return std::nullopt;
}

PursuitView ViewpointChooser::choose(const VehicleState& vehicle, const Vec3& uav, double t,
                                     double climb) const {
  const Vec3 target = vehicle.position + Vec3(0, 0, kBodyHeight);
  const Vec2 g = vehicle.position.head<2>();
  const double ground = vehicle.position.z();
  auto at = [&](const Vec2& xy, double height) {
    PursuitView v;
    v.position = Vec3(xy.x(), xy.y(), safeAltitude(xy, ground + height));
    // Face the vehicle, or along its heading from straight above it.
    const Vec2 to = g - xy;
    v.yaw = to.norm() > 1.0 ? std::atan2(to.y(), to.x()) : vehicle.yaw;
    return v;
  };
  auto candidate = [&](double bearing, double range, double height) {
    // bearing: from the vehicle's tail (0) counter-clockwise.
    const double a = vehicle.yaw + geometry::kPi + bearing;
    return at(g + range * Vec2(std::cos(a), std::sin(a)), height);
  };
  // Following an envelope, the climb stops where the candidates would leave its height band.
  const double max_climb =
      settings_.envelope_radius > 0.0 ? 0.4 * settings_.envelope_height : climb;
  const double h0 = settings_.height + std::clamp(climb, 0.0, std::max(0.0, max_climb));
  const PursuitView preferred = candidate(0.0, settings_.standoff, h0);
  if (usable(preferred.position, t)) {
    if (auto cam = seenBy(preferred.position, preferred.yaw, target)) {
      PursuitView v = preferred;
      v.visible = true;
      v.camera = *cam;
      return v;
    }
  }
  std::optional<PursuitView> seen, fallback;
  double seen_cost = std::numeric_limits<double>::infinity(), fallback_cost = seen_cost;
  // A candidate outside the keep-out zones, kept when it is the cheapest that sees the vehicle
  // (or, while none does, the cheapest): close to the preferred viewpoint, then to the UAV.
  auto consider = [&](PursuitView v) {
    if (!usable(v.position, t)) return;
    const double cost = (v.position - preferred.position).norm() + 0.5 * (v.position - uav).norm();
    if (cost >= seen_cost) return;
    if (const auto cam = seenBy(v.position, v.yaw, target)) {
      seen_cost = cost;
      v.visible = true;
      v.camera = *cam;
      seen = v;
    } else if (cost < fallback_cost) {
      fallback_cost = cost;
      fallback = v;
    }
  };
  if (settings_.envelope_radius > 0.0) {
    // Inside the envelope: the score is the envelope's, the sight line keeps the track.
    const Vec2 centre = preferred.position.head<2>();
    const double r = 0.6 * settings_.envelope_radius, dh = 0.6 * settings_.envelope_height;
    for (double h : {h0, h0 + dh, h0 - dh}) {
      for (int k = -1; k < 8; ++k) {
        const double a = k * geometry::kPi / 4.0;
        consider(at(k < 0 ? centre : centre + r * Vec2(std::cos(a), std::sin(a)), h));
      }
    }
    if (seen) return *seen;
    if (usable(preferred.position, t)) return preferred;
    if (fallback) return *fallback;
  }
  // The ring's scale: the standoff, at least 6 m (straight above, a ring of 0 m is one point).
  const double s = std::max(settings_.standoff, 6.0);
  const double ranges[] = {0.0, 0.5 * s, 1.5 * s + 4.0, 3.0 * s + 12.0};
  const double heights[] = {h0, h0 + 10.0};
  for (double h : heights) {
    for (double r : ranges) {
      for (int k = 0; k < 12; ++k) {
        if (r == 0.0 && k > 0) break;
        consider(candidate(k * geometry::kPi / 6.0, r, h));
      }
    }
  }
  if (seen) return *seen;
  if (fallback) return *fallback;
  return preferred;
}

}  // namespace hameritt::clients
