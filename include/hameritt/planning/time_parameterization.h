#pragma once
// Time parameterization of geometric UAV paths under speed, climb, descent and acceleration
// limits.

#include <vector>

#include "hameritt/geometry/types.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::planning {

// Kinematic limits of the UAV (defaults: the simulator's controller limits,
// docs/explanation/simulator.md).
struct SpeedLimits {
  double max_speed = 12.0;    // horizontal, m/s
  double climb_rate = 3.0;    // m/s
  double descent_rate = 2.0;  // m/s
  double accel = 2.0;         // along the path, m/s^2 (both speeding up and braking)
  // Throws scenario::ConfigError naming "planning.speed.<field>".
  void validate() const;
};

// Trapezoidal velocity profile along a polyline (forward-backward pass over the vertex speeds,
// after Kunz & Stilman's time-optimal path-following idea reduced to straight segments): the
// UAV starts and stops at rest, each segment's speed is capped by the horizontal, climb and
// descent limits for its direction, and each corner by its turning angle
// (cap * (1 + cos(turn)) / 2, so a reversal stops). Returns samples {t, x, y, z, yaw} at every
// vertex and at most `sample_spacing` metres apart in between, time from `t0`, yaw along the
// horizontal direction of travel, all rounded to 1e-3 (scenario::roundMilli). Between samples
// the trajectory is read by linear interpolation. Needs at least one point.
scenario::Trajectory timeParameterize(const std::vector<geometry::Vec3>& polyline, double t0,
                                      const SpeedLimits& limits, double sample_spacing = 1.0,
                                      double initial_yaw = 0.0);

// Length of a 3D polyline.
double pathLength(const std::vector<geometry::Vec3>& polyline);

}  // namespace hameritt::planning
