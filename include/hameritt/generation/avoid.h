#pragma once
// The avoid class: the generator's reference flight from the UAV's start to the goal (the
// shortest path that SPL compares the flown path with), the scripted trajectories of the other
// aircraft, and the checks that make an avoid scenario well-posed.

#include <string>
#include <vector>

#include "hameritt/planning/validity.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

// A flight from a start on the ground to a goal: a vertical take-off to the floor of the
// flight band, a flight inside the band, and, for a goal below the band (a landing spot), a
// vertical descent onto it.
struct ReferenceFlight {
  bool ok = false;
  std::string why;                   // why no flight was found (ok false)
  std::vector<geometry::Vec3> path;  // start, corners, goal
  double length = 0.0;               // metres
};

// The shortest such flight clear of the static obstacles and of the keep-out zones of
// `band` (each treated as active for the whole mission): Lazy Theta* (Nash, Koenig and
// Tovey, "Lazy Theta*: Any-Angle Path Planning and Path Length Analysis in 3D", AAAI 2010)
// on a grid of `cell` metres over the band, then shortcut where the straight segment is
// clear. Any-angle paths on a grid are within a few percent of the true shortest path; the
// take-off and descent columns are checked against the obstacles only. Deterministic.
ReferenceFlight shortestFlight(const planning::WorldValidity& band, const geometry::Vec3& start,
                               const geometry::Vec3& goal, double cell = 4.0);

// How an aircraft of an avoid scenario flies.
struct AircraftPattern {
  enum class Kind { kCrossing, kOrbit } kind = Kind::kCrossing;
  // kCrossing: back and forth along the chord from `a` to `b` at `speed`, passing `cross`
  // (a point of the chord) at `t_cross` heading for `b`.
  geometry::Vec3 a{0, 0, 0}, b{0, 0, 0}, cross{0, 0, 0};
  double t_cross = 0.0;
  // kOrbit: counter-clockwise circles of `radius` around `centre`, the height swinging by
  // +- `climb` over a lap.
  geometry::Vec3 centre{0, 0, 0};
  double radius = 30.0;
  double climb = 0.0;
  double phase = 0.0;  // rad, the angle at t = 0
  double speed = 10.0;
};

// The pattern as timed samples from t = 0 to `duration`, rounded to 1e-3, strictly increasing
// in t; yaw along the direction of travel, turning within half a second at a reversal.
Trajectory aircraftTrajectory(const AircraftPattern& pattern, double duration);

// Problems of an avoid scenario that the JSON schemas cannot see, each naming the file and
// field: the UAV start inside an obstacle or a zone (or an aircraft within the separation
// minimum at t = 0), a goal inside an obstacle or out of bounds, a stated shortest path
// shorter than the straight line or than the flight shortestFlight finds (by more than 1 %),
// aircraft trajectories that jump (faster than kMaxAircraftSpeed) or pass through the static
// obstacles. Empty when the scenario is well-posed.
std::vector<std::string> checkAvoidScenario(const World& world, const Mission& mission,
                                            const SimConfig& sim);

}  // namespace hameritt::scenario
