#pragma once
// Timed trajectories of movers: cars that follow the street network in their lane with a
// speed profile limited by acceleration and cornering, and pedestrians on sidewalk rings.

#include <optional>
#include <utility>
#include <vector>

#include "hameritt/geometry/oriented_box.h"
#include "hameritt/geometry/polygon.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::scenario {

// How a car drives a street path.
struct DriveSpec {
  double lane_offset = 1.55;      // lane centre to the right of the street centreline
  double corner_clearance = 6.0;  // straight lane segments stop this far from a node
  double cruise_speed = 10.0;
  double turn_speed = 4.5;
  double accel = 2.0;
  double decel = 3.0;
  double start_offset = 0.0;  // distance along the first edge where the car starts
  double start_time = 0.0;
  double depart_delay = 0.0;  // the car waits this long before moving
  // Starting at a kerb slot: the car pulls out from there into its lane.
  std::optional<geometry::Vec3> from_kerb;
  double from_kerb_yaw = 0.0;
};

// A timed trajectory along the street path (street centreline polyline through the nodes),
// driving on the right. Times, positions and yaw are rounded to 1e-3.
Trajectory planDrive(const std::vector<geometry::Vec2>& path, const DriveSpec& spec);

// A walk along a closed sidewalk ring from arc length s0 to s1 (either direction), waiting at
// s0 until t0.
Trajectory walkRing(const std::vector<geometry::Vec2>& ring, double s0, double s1, double speed,
                    double t0);

// `box` moved to a trajectory pose (its size kept; bottom at the pose's z).
geometry::OrientedBox poseBox(const geometry::OrientedBox& box, const TrajectoryPoint& p);

// The first contiguous time interval during which the trajectory's reference point is inside
// the convex polygon, computed exactly on the piecewise-linear path; nullopt if never.
std::optional<std::pair<double, double>> insideInterval(const Trajectory& traj,
                                                        const geometry::Polygon& convex);

// The other aircraft of an avoid scenario (SimConfig::aircraft) as scenario entities of class
// aircraft and role "aircraft", in their order, each with attribute "model": an aircraft's
// trajectory gives its body centre, an entity's the bottom of its box, so each sample is
// lowered by half the aircraft's height. Aircraft without a trajectory are left out.
std::vector<ScenarioEntity> aircraftEntities(const SimConfig& config);

}  // namespace hameritt::scenario
