// Keep-out zones that are building volumes in city area searches: the zone is a building's
// footprint grown by the stand-off, from the ground to the stand-off above the roof, clear of the
// target; the UAV's planned perception path never enters it while it is active (the checker
// flags a path through the zone: the negative control).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/trajectory.h"
#include "test_util.h"

namespace hameritt::scenario {
namespace {

using geometry::Vec2;
using testing::shippedConfig;

const World& cityWorld() { return testing::shippedCityWorld(); }

// The building whose volume the zone is (its footprint grown by 5 m, same centre and yaw), or
// nullptr.
const Entity* buildingOf(const World& w, const KeepOutZone& k) {
  if (k.polygon.size() != 4) return nullptr;
  Vec2 c(0, 0);
  for (const auto& p : k.polygon.vertices()) c += 0.25 * p;
  for (const auto& e : w.entities()) {
    if (e.cls != EntityClass::kBuilding || (e.box.center2() - c).norm() > 0.01) continue;
    const double a = (k.polygon.vertices()[1] - k.polygon.vertices()[0]).norm();
    const double b = (k.polygon.vertices()[2] - k.polygon.vertices()[1]).norm();
    if (std::abs(a - (e.box.size.x() + 10.0)) < 0.01 &&
        std::abs(b - (e.box.size.y() + 10.0)) < 0.01)
      return &e;
  }
  return nullptr;
}

// Samples (every 0.1 s) of a trajectory inside the zone's volume while it is active.
int samplesInside(const Trajectory& tr, const KeepOutZone& k) {
  int n = 0;
  for (double t = tr.front().t; t <= tr.back().t; t += 0.1) {
    const TrajectoryPoint p = sampleTrajectory(tr, t);
    if (!k.window.active(t) || !k.polygon.contains(Vec2(p.x, p.y))) continue;
    if (p.z >= k.alt_min.value_or(-1e9) && p.z <= k.alt_max.value_or(1e9)) ++n;
  }
  return n;
}

TEST(CityKoz, BuildingVolumesAreKeptOutOfByThePlannedPaths) {
  int scenarios = 0, zones = 0, paths = 0, near = 0, inside = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const Scenario s =
        generateScenario(cityWorld(), shippedConfig(), ScenarioClass::kAreaSearch, seed);
    ++scenarios;
    for (const auto& k : s.mission.kozs) {
      const Entity* b = buildingOf(cityWorld(), k);
      if (!b) continue;
      ++zones;
      EXPECT_EQ(k.purpose, "restricted");
      EXPECT_EQ(k.alt_min.value_or(-1), 0.0);
      EXPECT_GE(k.alt_max.value_or(0), b->box.maxZ() + 5.0);
      EXPECT_TRUE(s.mission.aois.front().polygon.contains(b->box.center2()));
      for (const auto& se : s.sim.entities) {
        if (se.role == "target") {
          EXPECT_FALSE(k.polygon.contains(se.entity.box.center2()));
        }
      }
      // Negative control: a path through the zone's middle at half its height is flagged.
      const Vec2 c = b->box.center2();
      const double z = 0.5 * *k.alt_max;
      const Trajectory through{{0, c.x() - 80, c.y(), z, 0}, {10, c.x() + 80, c.y(), z, 0}};
      EXPECT_GT(samplesInside(through, k), 0);
      if (!s.sim.uav.perception_path || s.sim.uav.perception_path->trajectory.empty()) continue;
      ++paths;
      const Trajectory& tr = s.sim.uav.perception_path->trajectory;
      inside += samplesInside(tr, k);
      // How often the path passes within 30 m of the zone (the zone is in its way).
      for (const auto& p : tr) near += k.polygon.distance(Vec2(p.x, p.y)) < 30.0 ? 1 : 0;
    }
  }
  EXPECT_EQ(scenarios, 10);
  EXPECT_GE(zones, 3);
  EXPECT_EQ(paths, zones);
  EXPECT_GT(near, 0);
  EXPECT_EQ(inside, 0);
  std::printf(
      "city area searches %d: building zones %d, perception paths %d, path points within "
      "30 m of a zone %d, samples inside %d\n",
      scenarios, zones, paths, near, inside);
}

}  // namespace
}  // namespace hameritt::scenario
