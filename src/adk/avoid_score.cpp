#include "hameritt/adk/avoid_score.h"

#include <cmath>
#include <cstdio>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {

namespace {
void requirePositive(double v, const char* field) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    throw scenario::ConfigError(std::string(field) + ": expected a positive number, got " +
                                scenario::formatNumber(v));
  }
}

SeparationMinimum minimumOf(const scenario::AvoidPhaseSpec& spec, double collision_radius) {
  SeparationMinimum m;
  m.horizontal = spec.min_horizontal_separation;
  m.vertical = spec.min_vertical_separation;
  m.collision_radius = collision_radius;
  return m;  // validated by the tracker
}
}  // namespace

AvoidScorer::AvoidScorer(const scenario::AvoidPhaseSpec& spec, double time_limit,
                         double collision_radius)
    : spec_(spec), time_limit_(time_limit), separation_(minimumOf(spec, collision_radius)) {
  requirePositive(spec.goal_radius, "avoid.goal_radius");
  requirePositive(spec.shortest_path_m, "avoid.shortest_path_m");
  requirePositive(time_limit, "avoid.time_limit");
}

void AvoidScorer::add(const TrafficSample& sample) {
  if (reach_time_) return;
  separation_.add(sample);  // validates before keeping anything
  if (last_position_) path_length_ += (sample.position - *last_position_).norm();
  last_position_ = sample.position;
  if ((sample.position - spec_.goal).norm() <= spec_.goal_radius) reach_time_ = sample.t;
}

AvoidScore AvoidScorer::score(double koz_seconds) const {
  AvoidScore s;
  s.shortest_path_m = spec_.shortest_path_m;
  s.koz_seconds = koz_seconds;
  s.reach_time = reach_time_;
  s.path_length_m = path_length_;
  if (last_position_) s.goal_distance_m = (*last_position_ - spec_.goal).norm();
  s.separation = separation_.score();
  if (!reach_time_) {
    s.failure =
        "did not come within " + scenario::formatNumber(spec_.goal_radius) + " m of the goal";
  } else if (*reach_time_ > time_limit_) {
    s.failure = "reached the goal after the time limit";
  } else if (s.separation.contact) {
    s.failure = "contact with " + s.separation.closest_aircraft;
  } else if (s.separation.losses > 0) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "lost separation %zu time(s), %.2f s in all",
                  s.separation.losses, s.separation.seconds_below_minimum);
    s.failure = buf;
  }
  s.success = s.failure.empty();
  NavigationEpisode e;
  e.success = s.success;
  e.shortest_path_m = spec_.shortest_path_m;
  e.path_length_m = s.path_length_m;
  s.spl = splOf(e);
  return s;
}

}  // namespace hameritt::adk
