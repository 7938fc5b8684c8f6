// The simulator with a city scenario loaded from its written sim_config.json: every traffic car
// and pedestrian is a kinematic Bullet body that follows its trajectory, so that a UAV hovering
// low over a lane is hit by the car that drives there (and, with the traffic taken out of the
// same scenario, is not: the negative control).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/trajectory.h"
#include "sim_test_util.h"

namespace hameritt::sim {
namespace {

using testing::calmConfig;
using testing::runUntil;
using testing::sentinel;

const scenario::World& cityWorld() {
  static const scenario::World w = [] {
    scenario::WorldParams p =
        scenario::loadWorldParams(scenario::defaultConfigDir() + "/world.json");
    p.type = scenario::WorldType::kCity;
    return scenario::generateWorld(p);
  }();
  return w;
}

// A city area search, written and read back.
const scenario::SimConfig& citySimConfig() {
  static const scenario::SimConfig c = [] {
    scenario::GeneratorConfig g =
        scenario::loadGeneratorConfig(scenario::defaultConfigDir() + "/generator.json");
    g.perception_paths = false;
    const scenario::Scenario s =
        scenario::generateScenario(cityWorld(), g, scenario::ScenarioClass::kAreaSearch, 3);
    return scenario::parseSimConfig(scenario::simConfigJson(s.sim), "sim_config.json");
  }();
  return c;
}

TEST(CitySimulation, TrafficCarsAreBulletBodiesThatHitALowUav) {
  const scenario::SimConfig& city = citySimConfig();
  int moving = 0, traffic = 0;
  for (const auto& se : city.entities) {
    if (!se.trajectory.empty()) ++moving;
    if (se.role == "traffic") ++traffic;
  }
  ASSERT_GE(traffic, 100);
  // A traffic car inside the tile that drives at least 5 m/s around t = 8 s: the UAV hovers
  // 1 m over the spot where its centre is then.
  const auto b = cityWorld().bounds();
  const scenario::ScenarioEntity* car = nullptr;
  geometry::Vec2 spot(0, 0);
  for (const auto& se : city.entities) {
    if (se.role != "traffic") continue;
    const auto p = scenario::sampleTrajectory(se.trajectory, 8.0);
    const auto q = scenario::sampleTrajectory(se.trajectory, 7.0);
    if (!b.contains(geometry::Vec2(p.x, p.y)) || std::hypot(p.x - q.x, p.y - q.y) < 5.0) continue;
    car = &se;
    spot = geometry::Vec2(p.x, p.y);
    break;
  }
  ASSERT_NE(car, nullptr);
  scenario::SimConfig c = city;
  c.environment = calmConfig().environment;
  c.uav.start = {0, spot.x(), spot.y(), 0, 0};
  Simulator sim(cityWorld(), c, sentinel(), SimSettings());
  EXPECT_EQ(sim.moverCount(), moving);
  sim.setPositionSetpoint({spot.x(), spot.y(), 1.0}, 0.0);
  ASSERT_TRUE(runUntil(sim, 12.0, [&] { return sim.uav().crashed; }));
  std::string role;
  for (const auto& se : city.entities) {
    if (se.entity.id == sim.uav().crashed_into) role = se.role;
  }
  EXPECT_EQ(role, "traffic") << sim.uav().crashed_into;
  EXPECT_LT(sim.uav().crash_time, 9.0);

  // Negative control: the same scenario without its traffic and crowd; the UAV hovers on.
  scenario::SimConfig quiet = c;
  quiet.entities.clear();
  for (const auto& se : c.entities) {
    if (se.role != "traffic" && se.role != "pedestrian") quiet.entities.push_back(se);
  }
  Simulator calm(cityWorld(), quiet, sentinel(), SimSettings());
  calm.setPositionSetpoint({spot.x(), spot.y(), 1.0}, 0.0);
  EXPECT_FALSE(runUntil(calm, 12.0, [&] { return calm.uav().crashed; }));
  std::printf("city scenario: %d movers (%d traffic cars) in Bullet; hit by %s at %.2f s\n",
              sim.moverCount(), traffic, sim.uav().crashed_into.c_str(), sim.uav().crash_time);
}

}  // namespace
}  // namespace hameritt::sim
