#include "hameritt/adk/navigation_metrics.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {
namespace {

using geometry::Vec3;

std::string num(double v) { return scenario::formatNumber(v); }

void requireFinite(const Vec3& v, const std::string& field) {
  if (!v.allFinite()) throw InputError(field + ": expected finite coordinates");
}

void requireIncreasing(double t, double prev, std::size_t i) {
  if (!std::isfinite(t)) throw InputError("sample " + std::to_string(i) + ": t is not finite");
  if (i > 0 && !(t > prev)) {
    throw InputError("sample " + std::to_string(i) + ": t = " + num(t) +
                     " does not come after the previous sample's " + num(prev));
  }
}

void requirePositive(double v, const std::string& field) {
  if (!(v > 0.0 && std::isfinite(v))) {
    throw scenario::ConfigError(field + ": expected a finite number > 0, got " + num(v));
  }
}

void requireNonNegative(double v, const std::string& field) {
  if (!(v >= 0.0 && std::isfinite(v))) {
    throw scenario::ConfigError(field + ": expected a finite number >= 0, got " + num(v));
  }
}

}  // namespace

double splOf(const NavigationEpisode& e) {
  if (!(e.shortest_path_m > 0.0 && std::isfinite(e.shortest_path_m))) {
    throw InputError("shortest_path_m: expected a finite number > 0, got " +
                     num(e.shortest_path_m));
  }
  if (!(e.path_length_m >= 0.0 && std::isfinite(e.path_length_m))) {
    throw InputError("path_length_m: expected a finite number >= 0, got " + num(e.path_length_m));
  }
  if (!e.success) return 0.0;
  return e.shortest_path_m / std::max(e.path_length_m, e.shortest_path_m);
}

double spl(const std::vector<NavigationEpisode>& episodes) {
  if (episodes.empty()) throw InputError("spl: no episodes");
  double sum = 0.0;
  for (const auto& e : episodes) sum += splOf(e);
  return sum / episodes.size();
}

double pathLength(const std::vector<Vec3>& points) {
  double l = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) l += (points[i] - points[i - 1]).norm();
  return l;
}

void SeparationMinimum::validate() const {
  requirePositive(horizontal, "separation.horizontal");
  requirePositive(vertical, "separation.vertical");
  requireNonNegative(collision_radius, "separation.collision_radius");
}

double timeToCollision(const Vec3& p, const Vec3& v, double radius) {
  const double c = p.squaredNorm() - radius * radius;
  if (c <= 0.0) return 0.0;
  const double a = v.squaredNorm();
  const double b = p.dot(v);
  if (a <= 0.0 || b >= 0.0) return kNever;  // still, or not closing
  const double disc = b * b - a * c;
  if (disc < 0.0) return kNever;  // passes wide
  return (-b - std::sqrt(disc)) / a;
}

SeparationTracker::SeparationTracker(const SeparationMinimum& minimum) : minimum_(minimum) {
  minimum_.validate();
}

void SeparationTracker::add(const TrafficSample& x) {
  requireIncreasing(x.t, count_ ? last_t_ : 0.0, count_);
  const std::string at = "sample " + std::to_string(count_);
  requireFinite(x.position, at + ": position");
  requireFinite(x.velocity, at + ": velocity");
  std::set<std::string> ids;
  for (const auto& a : x.aircraft) {
    if (!ids.insert(a.id).second) throw InputError(at + ": aircraft " + a.id + " occurs twice");
    requireFinite(a.position, at + ": aircraft " + a.id + " position");
    requireFinite(a.velocity, at + ": aircraft " + a.id + " velocity");
  }
  // Valid: now kept. The previous sample's loss holds until this one (sample-and-hold).
  if (count_ > 0 && last_lost_) score_.seconds_below_minimum += x.t - last_t_;
  bool lost = false;
  for (const auto& a : x.aircraft) {
    const Vec3 p = a.position - x.position;
    const double d = p.norm();
    if (d < score_.min_distance_m) {
      score_.min_distance_m = d;
      score_.closest_aircraft = a.id;
      score_.min_distance_t = x.t;
    }
    if (d < minimum_.collision_radius) score_.contact = true;
    if (p.head<2>().norm() < minimum_.horizontal && std::fabs(p.z()) < minimum_.vertical) {
      lost = true;
    }
    const double ttc = timeToCollision(p, a.velocity - x.velocity, minimum_.collision_radius);
    if (ttc < score_.min_time_to_collision_s) {
      score_.min_time_to_collision_s = ttc;
      score_.time_to_collision_aircraft = a.id;
    }
  }
  if (lost && !last_lost_) ++score_.losses;
  last_lost_ = lost;
  last_t_ = x.t;
  ++count_;
}

SeparationScore scoreSeparation(const std::vector<TrafficSample>& samples,
                                const SeparationMinimum& minimum) {
  SeparationTracker tracker(minimum);
  for (const auto& x : samples) tracker.add(x);
  return tracker.score();
}

void FollowEnvelope::validate() const {
  requireNonNegative(distance, "envelope.distance");
  requirePositive(distance_tolerance, "envelope.distance_tolerance");
  if (!std::isfinite(height)) {
    throw scenario::ConfigError("envelope.height: expected a finite number, got " + num(height));
  }
  requirePositive(height_tolerance, "envelope.height_tolerance");
}

namespace {

// Horizontal distance from the point d* behind the target, and the height error.
std::pair<double, double> envelopeErrors(const FollowSample& s, const FollowEnvelope& e) {
  const geometry::Vec2 forward(std::cos(s.target_yaw), std::sin(s.target_yaw));
  const geometry::Vec2 desired = s.target.head<2>() - e.distance * forward;
  return {(s.vehicle.head<2>() - desired).norm(), s.vehicle.z() - s.target.z() - e.height};
}

}  // namespace

bool insideEnvelope(const FollowSample& s, const FollowEnvelope& e) {
  const auto [d, h] = envelopeErrors(s, e);
  return d <= e.distance_tolerance && std::fabs(h) <= e.height_tolerance;
}

FollowScore scoreFollow(const std::vector<FollowSample>& samples, const FollowEnvelope& e) {
  FollowAccumulator a(e);
  for (const auto& s : samples) a.add(s);
  return a.result();
}

FollowAccumulator::FollowAccumulator(const FollowEnvelope& envelope) : e_(envelope) {
  e_.validate();
}

void FollowAccumulator::add(const FollowSample& s) {
  requireIncreasing(s.t, n_ ? last_t_ : 0.0, n_);
  // (The message is only built for a bad sample.)
  if (!s.vehicle.allFinite() || !s.target.allFinite() || !std::isfinite(s.target_yaw)) {
    const std::string at = "sample " + std::to_string(n_);
    requireFinite(s.vehicle, at + ": vehicle");
    requireFinite(s.target, at + ": target");
    throw InputError(at + ": target_yaw is not finite");
  }
  const auto [d, h] = envelopeErrors(s, e_);
  const bool in = d <= e_.distance_tolerance && std::fabs(h) <= e_.height_tolerance;
  // The previous sample holds until this one.
  if (n_ > 0) {
    const double dt = s.t - last_t_;
    if (last_in_) inside_s_ += dt;
    if (last_los_) los_s_ += dt;
  } else {
    first_t_ = s.t;
  }
  dist_.push_back(d);
  sum_d2_ += d * d;
  sum_h2_ += h * h;
  if (!in && !outside_) {
    outside_ = true;
    outside_since_ = s.t;
  } else if (in && outside_) {
    outside_ = false;
    longest_outside_ = std::max(longest_outside_, s.t - outside_since_);
  }
  ++n_;
  last_t_ = s.t;
  last_in_ = in;
  last_los_ = s.line_of_sight;
}

FollowScore FollowAccumulator::result() const {
  FollowScore r;
  r.samples = n_;
  if (n_ == 0) return r;
  r.longest_outside_s = longest_outside_;
  if (outside_) r.longest_outside_s = std::max(r.longest_outside_s, last_t_ - outside_since_);
  r.duration_s = last_t_ - first_t_;
  if (r.duration_s > 0.0) {
    r.inside_fraction = inside_s_ / r.duration_s;
    r.line_of_sight_fraction = los_s_ / r.duration_s;
  }
  const double n = static_cast<double>(n_);
  r.rms_distance_error_m = std::sqrt(sum_d2_ / n);
  r.rms_height_error_m = std::sqrt(sum_h2_ / n);
  const std::size_t rank = (95 * n_ + 99) / 100;  // ceil(0.95 n), in integers
  std::vector<double> dist = dist_;
  std::nth_element(dist.begin(), dist.begin() + static_cast<std::ptrdiff_t>(rank - 1), dist.end());
  r.p95_distance_error_m = dist[rank - 1];
  return r;
}

}  // namespace hameritt::adk
