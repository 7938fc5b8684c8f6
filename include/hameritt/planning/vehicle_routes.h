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

// Where a car that ends its route on a street stops: with its front before the intersection
// ahead (the crossing streets' carriageway and crosswalks), and on a wide street (the lanes that
// the city's traffic drives) at the kerb, out of the lanes. validate() throws ConfigError naming
// "kerb_stop.<field>".
struct KerbStop {
  double sidewalk_width = 1.8;  // crosswalk depth beyond a crossing street's kerb (m)
  double stop_back = 1.0;       // the front stays this far before the crosswalk (m)
  // Streets at least this wide are pulled over on (m); narrower ones keep the car in its lane.
  double kerb_street_width = 20.0;
  double kerb_gap = 0.5;    // between the car's side and the kerb (m)
  double decel = 2.0;       // preferred braking to the stop (m/s^2)
  double max_decel = 3.0;   // the most braking accepted (m/s^2)
  double min_run = 30.0;    // the shortest stretch of the final straight used (m)
  double max_slope = 0.35;  // the most sideways drift per metre along the street
  // A car stopped ahead in the same lane (a convoy's lead): the centre stops `follow_gap`
  // behind its centre.
  std::optional<scenario::TrajectoryPoint> behind;
  double follow_gap = 12.0;
  void validate() const;
};

struct KerbStopResult {
  // False when the stop had to move (into the intersection, onto the car ahead) but could not
  // (a short final straight, too hard braking, an obstacle at the kerb): the trajectory is then
  // the input unchanged.
  bool ok = true;
  bool changed = false;  // the trajectory's tail was replaced
  bool at_kerb = false;  // it ends at the kerb
  scenario::Trajectory trajectory;
};

// Replaces the tail of a car's trajectory (ending at rest, on the straight of its final street,
// as planVehicleRoute and scenario::planDrive leave it) by a stop before the intersection ahead
// and, on a wide street, a cosine blend to the kerb while it brakes at constant deceleration
// from its speed where the blend starts. Unchanged (ok) where it already stops clear. The car's
// footprint (settings.vehicle_length x vehicle_width) stays on the street and off the world's
// obstacles. Deterministic; times and positions rounded to the millimetre.
KerbStopResult stopAtKerb(const scenario::World& world, const scenario::Trajectory& traj,
                          const KerbStop& stop, const RouteSettings& settings = {});

// Drops the structures kept per world for vehicle routes (street index, validated route
// pieces); the next route on a world builds them again. Routes do not depend on them.
void clearRouteCaches();

// True when the point is within `half_width` of some street centreline (the street surface
// shrunk by the rest of the street half-width).
bool onStreet(const scenario::World& world, const geometry::Vec2& p, double shrink = 0.0);

}  // namespace hameritt::planning
