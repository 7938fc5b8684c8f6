#pragma once
// Car routes on the street network: a seeded graph search gives varied routes, Dubins curves
// (OMPL) join the lane segments, driving on the right, and a speed profile gives a timed
// trajectory. For the scenario generator's target and traffic cars.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hameritt/planning/uav_planner.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::planning {

// How fast a car drives (docs/reference/conventions.md: 2 m/s^2, 3 m/s^2 braking, 4.5 m/s corners).
// validate() throws scenario::ConfigError naming "route.speed.<field>".
struct SpeedProfile {
  double cruise_speed = 10.0;
  double accel = 2.0;
  double decel = 3.0;
  double corner_speed = 4.5;
  void validate() const;
};

// Route geometry and variability. validate() throws ConfigError naming "route.<field>".
struct RouteSettings {
  double lane_offset = 1.55;      // lane centre right of the street centreline
  double corner_clearance = 6.0;  // lanes end this far before an intersection
  double turn_radius = 4.0;       // Dubins minimum turning radius (halved up to twice if needed)
  double cost_noise = 0.35;       // edge cost = length * (1 + cost_noise * U[0, 1)), per seed
  double vehicle_length = 4.6;    // footprint kept clear of parked cars
  double vehicle_width = 1.9;     // and inside the street surface
  double sample_spacing = 2.0;    // output samples at most this far apart on straights, metres
  void validate() const;
};

// The destination: a street node (the car stops in its lane before it) or a pose on a lane.
struct RouteGoal {
  int node = -1;
  std::optional<scenario::TrajectoryPoint> pose;  // used when set (x, y, yaw)
};

struct RouteResult {
  PlanStatus status = PlanStatus::kNoSolution;
  std::string message;
  scenario::Trajectory trajectory;  // {t, x, y, z = 0, yaw}, rounded to 1e-3
  std::vector<int> nodes;           // street nodes passed, in order
  double length = 0.0;
  bool ok() const { return status == PlanStatus::kExact; }
};

// Plans a car route from `start` (a pose in a lane; start.t is the departure time) to `goal`.
// Dijkstra (1959) over the street graph with seeded multiplicative edge-cost noise (different
// seeds give different reasonable routes, no U-turns), then lane waypoints joined by Dubins
// (1957) shortest curves (ompl::base::DubinsStateSpace) whose samples (every 0.25 m) are
// checked to keep the car's footprint on the street surface (within street_width / 2 of a
// centreline) and off every parked car; finally a speed profile with acceleration, braking and
// corner limits. Deterministic for a given seed. Statuses: kInvalidStart (not on a street),
// kInvalidGoal (unknown node, pose off street), kNoSolution (unreachable, or no valid curve).
RouteResult planVehicleRoute(const scenario::World& world, const scenario::TrajectoryPoint& start,
                             const RouteGoal& goal, std::uint64_t seed,
                             const SpeedProfile& speed = {}, const RouteSettings& settings = {});

// Drops the structures kept per world for vehicle routes (street index, validated route
// pieces); the next route on a world builds them again. Routes do not depend on them.
void clearRouteCaches();

// True when the point is within `half_width` of some street centreline (the street surface
// shrunk by the rest of the street half-width).
bool onStreet(const scenario::World& world, const geometry::Vec2& p, double shrink = 0.0);

}  // namespace hameritt::planning
