#pragma once

// Fixtures shared by the SITL server gtests: the shipped quadrotor and a calm, windless world.

#include "hameritt/scenario/scenario.h"
#include "hameritt/sim/quadrotor.h"

namespace hameritt::sitl::test {

// The shipped quadrotor model, loaded once.
inline const sim::QuadrotorParams& sentinel() {
  static const sim::QuadrotorParams p = sim::loadQuadrotorUrdf(sim::defaultQuadrotorUrdf());
  return p;
}

// A sim config with the UAV at the origin, no wind, seed 3.
inline scenario::SimConfig calm() {
  scenario::SimConfig c;
  c.seed = 3;
  c.duration = 600;
  c.uav.start = {0, 0, 0, 0, 0};
  c.uav.max_speed = 12;
  return c;
}

}  // namespace hameritt::sitl::test
