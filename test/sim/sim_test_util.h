#pragma once
// Shared fixtures of the simulator tests: the shipped world, model and default scenario (built
// once), and small scenario builders.

#include "hameritt/build_paths.h"
#include <string>

#include "hameritt/generation/generator.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/world.h"
#include "hameritt/sim/quadrotor.h"
#include "hameritt/sim/simulator.h"

namespace hameritt::sim::testing {

inline const scenario::World& shippedWorld() {
  static const scenario::World w = scenario::generateWorld(
      scenario::loadWorldParams(scenario::defaultConfigDir() + "/world.json"));
  return w;
}

inline const scenario::World& emptyWorld() {
  static const scenario::World w;
  return w;
}

inline const QuadrotorParams& sentinel() {
  static const QuadrotorParams p = loadQuadrotorUrdf(defaultQuadrotorUrdf());
  return p;
}

inline std::string defaultScenarioDir() {
  return std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default";
}

inline const scenario::SimConfig& defaultSimConfig() {
  static const scenario::SimConfig c =
      scenario::loadSimConfig(defaultScenarioDir() + "/sim_config.json");
  return c;
}

// An empty scenario: the UAV at the origin, calm air.
inline scenario::SimConfig calmConfig(std::uint64_t seed = 7) {
  scenario::SimConfig c;
  c.seed = seed;
  c.duration = 600;
  c.uav.start = {0, 0, 0, 0, 0};
  c.uav.max_speed = 12.0;
  return c;
}

// Steps until pred() holds or `max_s` seconds pass; returns whether it held.
template <typename Pred>
bool runUntil(Simulator& sim, double max_s, Pred pred) {
  const int n = static_cast<int>(max_s / sim.dt());
  for (int i = 0; i < n; ++i) {
    sim.step();
    if (pred()) return true;
  }
  return false;
}

}  // namespace hameritt::sim::testing
