// The avoid baseline's pilot, flown in closed loop on a point-mass UAV (speed-limited, first
// order towards the setpoint) against generated avoid scenarios, the aircraft reported at 2 Hz
// as the ADK's traffic topic reports them: it reaches the goal inside the time limit and never
// loses separation. The generated aircraft rarely force a conflict on this point mass (flown
// blind, the closest is 5.7 m), so an aircraft flying head-on along the pilot's own path is the
// test that separates a pilot that avoids from one that does not: told nothing about it (the
// negative control), the same flight loses separation.
#include "hameritt/clients/avoid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "hameritt/generation/generator.h"
#include "hameritt/geometry/polygon.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/world.h"
#include "../scenario/test_util.h"

namespace hameritt::clients {
namespace {

using geometry::Vec3;

// The shipped configuration and worlds, built once (the scenario tests' fixtures).
const scenario::GeneratorConfig& config() { return scenario::testing::shippedConfig(); }
const scenario::World& suburb() { return scenario::testing::shippedWorld(); }
const scenario::World& city() { return scenario::testing::shippedCityWorld(); }

const scenario::AvoidPhaseSpec& avoidSpec(const scenario::Mission& m) {
  for (const auto& p : m.phases) {
    if (p.type == scenario::PhaseType::kAvoid) return p.avoid;
  }
  throw std::runtime_error("no avoid phase");
}

Vec3 aircraftAt(const scenario::Aircraft& a, double t) {
  const scenario::TrajectoryPoint q = scenario::sampleTrajectory(a.trajectory, t);
  return Vec3(q.x, q.y, q.z);
}

struct Flight {
  bool reached = false;
  double reach_time = 0.0;
  double min_separation = std::numeric_limits<double>::infinity();  // 3D, to any aircraft
  bool lost = false;  // horizontal < 5 m and vertical < 3 m at some step
  int conflicts = 0;  // ticks where the pilot found no clear candidate
};

// Flies the scenario at 20 Hz (pilot at 10 Hz, traffic reports at 2 Hz) until the UAV is
// within the goal radius or the time limit passes. `report` false: the pilot hears nothing.
Flight fly(const scenario::World& world, const scenario::Scenario& sc,
           const std::vector<scenario::Aircraft>& fleet, bool report) {
  const scenario::AvoidPhaseSpec& spec = avoidSpec(sc.mission);
  AvoidPilot pilot(world, sc.mission, sc.sim.uav);
  Vec3 p(sc.sim.uav.start.x, sc.sim.uav.start.y, 0.0);
  EXPECT_TRUE(pilot.plan(p)) << pilot.why();
  const double dt = 0.05, vmax = sc.sim.uav.max_speed;
  Vec3 setpoint = p;
  Flight f;
  for (int i = 0; i * dt <= sc.mission.time_limit; ++i) {
    const double t = i * dt;
    if (report && i % 10 == 0) {
      for (const auto& a : fleet) {
        pilot.observe(
            {a.id, t, aircraftAt(a, t), (aircraftAt(a, t + 0.05) - aircraftAt(a, t - 0.05)) / 0.1});
      }
    }
    if (i % 2 == 0) {
      const AvoidCommand c = pilot.step(t, p);
      setpoint = c.setpoint;
      f.conflicts += c.conflict ? 1 : 0;
    }
    Vec3 v = (setpoint - p) * 1.5;
    if (v.norm() > vmax) v *= vmax / v.norm();
    p += v * dt;
    for (const auto& a : fleet) {
      const Vec3 q = aircraftAt(a, t);
      f.min_separation = std::min(f.min_separation, (p - q).norm());
      if ((p - q).head<2>().norm() < spec.min_horizontal_separation &&
          std::abs(p.z() - q.z()) < spec.min_vertical_separation) {
        f.lost = true;
      }
    }
    if ((p - spec.goal).norm() <= spec.goal_radius) {
      f.reached = true;
      f.reach_time = t;
      break;
    }
  }
  return f;
}

// An aircraft that flies the pilot's own path backwards, 1 m above it, from the goal end at
// 8 m/s, starting when the UAV has climbed: head-on.
scenario::Aircraft headOn(const AvoidPilot& pilot, double start_t) {
  scenario::Aircraft a;
  a.id = "intruder";
  a.model = "quadrotor";
  a.size = Vec3(0.6, 0.6, 0.25);
  const double len = pilot.pathLength();
  const double speed = 8.0;
  for (double u = 0.0; u <= len; u += 2.0) {
    const Vec3 q = pilot.pointAt(len - u) + Vec3(0, 0, 1.0);
    if (q.z() < 10.0) continue;  // the band only, not the columns
    a.trajectory.push_back({start_t + u / speed, q.x(), q.y(), q.z(), 0.0});
  }
  // Before its start it waits at the first point.
  if (!a.trajectory.empty()) {
    auto first = a.trajectory.front();
    first.t = 0.0;
    a.trajectory.insert(a.trajectory.begin(), first);
  }
  return a;
}

void flyGenerated(const scenario::World& world, int n) {
  int reached = 0, clean = 0;
  for (int seed = 1; seed <= n; ++seed) {
    const scenario::Scenario sc =
        scenario::generateScenario(world, config(), scenario::ScenarioClass::kAvoid, seed);
    SCOPED_TRACE(sc.mission.scenario_id);
    const Flight f = fly(world, sc, sc.sim.aircraft, true);
    reached += f.reached ? 1 : 0;
    clean += f.reached && !f.lost ? 1 : 0;
    EXPECT_TRUE(f.reached) << "time limit " << sc.mission.time_limit;
    EXPECT_FALSE(f.lost) << "closest " << f.min_separation << " m";
    std::printf("seed %d: reached %d at %.1f s of %.0f, closest %.1f m, %d conflict ticks\n", seed,
                f.reached, f.reach_time, sc.mission.time_limit, f.min_separation, f.conflicts);
  }
  ::testing::Test::RecordProperty("reached", reached);
  ::testing::Test::RecordProperty("clean", clean);
}

TEST(AvoidPilot, ReachesTheGoalWithoutLosingSeparationOnGeneratedScenarios) {
  flyGenerated(suburb(), 12);
}

// Among the city's towers the path is longer and the aircraft fly lower chords.
TEST(AvoidPilot, ReachesTheGoalWithoutLosingSeparationInTheCity) { flyGenerated(city(), 6); }

TEST(AvoidPilot, AHeadOnAircraftIsAvoidedOnlyWhenReported) {
  const scenario::Scenario sc =
      scenario::generateScenario(suburb(), config(), scenario::ScenarioClass::kAvoid, 3);
  AvoidPilot probe(suburb(), sc.mission, sc.sim.uav);
  ASSERT_TRUE(probe.plan(Vec3(sc.sim.uav.start.x, sc.sim.uav.start.y, 0.0)));
  const std::vector<scenario::Aircraft> fleet{headOn(probe, 5.0)};
  ASSERT_GT(fleet.front().trajectory.size(), 10u);
  const Flight heard = fly(suburb(), sc, fleet, true);
  EXPECT_TRUE(heard.reached);
  EXPECT_FALSE(heard.lost) << "closest " << heard.min_separation << " m";
  // The negative control: told nothing, the pilot flies into it.
  const Flight deaf = fly(suburb(), sc, fleet, false);
  EXPECT_TRUE(deaf.lost) << "closest " << deaf.min_separation << " m";
}

// A moving zone (a hostile vehicle's escort) that parks on the path for good: the pilot holds,
// then plans again around the zone where it stands, reaches the goal and never enters it.
TEST(AvoidPilot, PlansAgainAroundAMovingZoneParkedOnThePath) {
  scenario::Scenario sc =
      scenario::generateScenario(suburb(), config(), scenario::ScenarioClass::kAvoid, 3);
  AvoidPilot probe(suburb(), sc.mission, sc.sim.uav);
  ASSERT_TRUE(probe.plan(Vec3(sc.sim.uav.start.x, sc.sim.uav.start.y, 0.0)));
  const Vec3 mid = probe.pointAt(0.5 * probe.pathLength());
  scenario::KeepOutZone k;
  k.id = "koz_parked";
  k.purpose = "restricted";
  k.polygon = geometry::orientedRectangle(mid.head<2>(), 30.0, 30.0, 0.0);
  k.alt_min = 0.0;
  k.alt_max = sc.sim.uav.altitude_max + 20.0;
  k.motion = {{0.0, mid.x(), mid.y(), 0.0, 0.0}, {1000.0, mid.x(), mid.y(), 0.0, 0.0}};
  // Only this moving zone: the generated escort is dropped.
  std::vector<scenario::KeepOutZone> zones;
  for (const auto& z : sc.mission.kozs) {
    if (z.motion.empty()) zones.push_back(z);
  }
  zones.push_back(k);
  sc.mission.kozs = zones;
  AvoidPilot pilot(suburb(), sc.mission, sc.sim.uav);
  Vec3 p(sc.sim.uav.start.x, sc.sim.uav.start.y, 0.0);
  ASSERT_TRUE(pilot.plan(p));
  const scenario::AvoidPhaseSpec& spec = avoidSpec(sc.mission);
  Vec3 setpoint = p;
  bool reached = false, entered = false;
  for (int i = 0; i * 0.05 <= sc.mission.time_limit && !reached; ++i) {
    if (i % 2 == 0) setpoint = pilot.step(i * 0.05, p).setpoint;
    Vec3 v = (setpoint - p) * 1.5;
    if (v.norm() > sc.sim.uav.max_speed) v *= sc.sim.uav.max_speed / v.norm();
    p += v * 0.05;
    entered |= k.polygon.contains(p.head<2>());
    reached = (p - spec.goal).norm() <= spec.goal_radius;
  }
  EXPECT_TRUE(reached) << "at (" << p.transpose() << "), " << pilot.replans() << " replans, path "
                       << pilot.pathLength() << " m: " << pilot.why();
  EXPECT_FALSE(entered);
  EXPECT_GE(pilot.replans(), 1);
}

TEST(AvoidPilot, AStaleReportIsDroppedAndAnOlderOneIgnored) {
  const scenario::Scenario sc =
      scenario::generateScenario(suburb(), config(), scenario::ScenarioClass::kAvoid, 5);
  AvoidPilot pilot(suburb(), sc.mission, sc.sim.uav);
  ASSERT_TRUE(pilot.plan(Vec3(sc.sim.uav.start.x, sc.sim.uav.start.y, 0.0)));
  pilot.observe({"a", 2.0, Vec3(0, 0, 30), Vec3(1, 0, 0)});
  pilot.observe({"a", 1.0, Vec3(5, 0, 30), Vec3(1, 0, 0)});            // older: ignored
  pilot.observe({"b", 2.0, Vec3(0, 0, std::nan("")), Vec3(0, 0, 0)});  // not finite: ignored
  EXPECT_EQ(pilot.tracked(), 1u);
  pilot.step(2.5, Vec3(sc.sim.uav.start.x, sc.sim.uav.start.y, 0.0));
  EXPECT_EQ(pilot.tracked(), 1u);
  pilot.step(6.0, Vec3(sc.sim.uav.start.x, sc.sim.uav.start.y, 0.0));  // 4 s old: dropped
  EXPECT_EQ(pilot.tracked(), 0u);
}

TEST(AvoidPilot, RefusesAMissionWithoutAnAvoidPhaseAndBadSettings) {
  const scenario::Scenario sc =
      scenario::generateScenario(suburb(), config(), scenario::ScenarioClass::kAreaSearch, 1);
  EXPECT_THROW(AvoidPilot(suburb(), sc.mission, sc.sim.uav), scenario::ConfigError);
  const scenario::Scenario av =
      scenario::generateScenario(suburb(), config(), scenario::ScenarioClass::kAvoid, 1);
  AvoidSettings bad;
  bad.horizon = 0.0;
  try {
    AvoidPilot(suburb(), av.mission, av.sim.uav, bad);
    ADD_FAILURE() << "no error";
  } catch (const scenario::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("avoid.horizon"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hameritt::clients
