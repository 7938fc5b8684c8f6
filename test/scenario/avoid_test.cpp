// The avoid class: generated scenarios are well-posed (checked by checkAvoidScenario, the
// schemas and the semantic validator), deterministic, in the suburb and the city; the
// reference flight is the shortest around what blocks it; aircraft patterns are continuous;
// and every check catches a doctored scenario (the negative controls).
#include "hameritt/generation/avoid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "hameritt/geometry/segment.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/validation.h"
#include "test_util.h"

using namespace hameritt::scenario;
using hameritt::geometry::Vec2;
using hameritt::geometry::Vec3;
using hameritt::scenario::testing::shippedConfig;
using hameritt::scenario::testing::shippedWorld;

namespace {

const World& cityWorld() {
  static const World w = [] {
    WorldParams p = loadWorldParams(defaultConfigDir() + "/world.json");
    p.type = WorldType::kCity;
    return generateWorld(p);
  }();
  return w;
}

const AvoidPhaseSpec& avoidSpec(const Scenario& s) {
  for (const auto& p : s.mission.phases) {
    if (p.type == PhaseType::kAvoid) return p.avoid;
  }
  throw std::runtime_error("no avoid phase");
}

std::vector<ValidationIssue> schemaIssues(const std::string& text, const std::string& name) {
  return validateDocument(nlohmann::json::parse(text), name, defaultConfigDir() + "/schema");
}

std::string joined(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += s + "\n";
  return out;
}

bool mentions(const std::vector<std::string>& v, const std::string& what) {
  for (const auto& s : v) {
    if (s.find(what) != std::string::npos) return true;
  }
  return false;
}

// The aircraft's 2D track crosses the polyline.
bool crosses(const Trajectory& traj, const std::vector<Vec2>& line) {
  for (std::size_t i = 1; i < traj.size(); ++i) {
    for (std::size_t k = 1; k < line.size(); ++k) {
      if (hameritt::geometry::segmentsIntersect(Vec2(traj[i - 1].x, traj[i - 1].y),
                                                Vec2(traj[i].x, traj[i].y), line[k - 1], line[k])) {
        return true;
      }
    }
  }
  return false;
}

// Everything a generated avoid scenario promises, checked from the outside of the generator.
void expectWellPosed(const World& w, const Scenario& s) {
  SCOPED_TRACE(s.mission.scenario_id);
  EXPECT_TRUE(checkAvoidScenario(w, s.mission, s.sim).empty())
      << joined(checkAvoidScenario(w, s.mission, s.sim));
  const AvoidPhaseSpec& a = avoidSpec(s);
  const Vec3 start(s.sim.uav.start.x, s.sim.uav.start.y, s.sim.uav.start.z);
  EXPECT_GE(a.shortest_path_m, (a.goal - start).norm());
  EXPECT_GE(s.sim.aircraft.size(), 2u);
  EXPECT_LE(s.sim.aircraft.size(), 6u);
  EXPECT_EQ(s.mission.objective.type, "reach");
  EXPECT_TRUE(s.mission.objective.targets.empty());
  EXPECT_GT(s.mission.time_limit, a.shortest_path_m / s.sim.uav.max_speed);
  EXPECT_EQ(s.sim.duration, s.mission.time_limit);
  // At least one aircraft crosses the reference flight.
  std::vector<KeepOutZone> statics;
  for (const auto& k : s.mission.kozs) {
    if (k.motion.empty()) statics.push_back(k);
  }
  const hameritt::planning::WorldValidity band(w, statics,
                                               hameritt::planning::validitySettingsFor(s.sim.uav));
  const ReferenceFlight ref = shortestFlight(band, start, a.goal);
  ASSERT_TRUE(ref.ok) << ref.why;
  std::vector<Vec2> ref2;
  for (const auto& p : ref.path) ref2.push_back(Vec2(p.x(), p.y()));
  int crossing = 0;
  for (const auto& ac : s.sim.aircraft) {
    crossing += crosses(ac.trajectory, ref2) ? 1 : 0;
    EXPECT_LE(ac.trajectory.front().t, 0.0);
    EXPECT_GE(ac.trajectory.back().t, s.mission.time_limit);
  }
  EXPECT_GE(crossing, 1);
  // Exactly one moving zone, escorting the hostile vehicle along its whole trajectory.
  const ScenarioEntity* hostile = nullptr;
  for (const auto& e : s.sim.entities) {
    if (e.role == "hostile") hostile = &e;
  }
  ASSERT_NE(hostile, nullptr);
  int moving = 0;
  for (const auto& k : s.mission.kozs) {
    if (k.motion.empty()) continue;
    ++moving;
    for (double t = 0.0; t <= s.mission.time_limit; t += 7.5) {
      const TrajectoryPoint car = sampleTrajectory(hostile->trajectory, t);
      const Vec2 c = kozPolygonAt(k, t).bounds().min * 0.5 + kozPolygonAt(k, t).bounds().max * 0.5;
      EXPECT_NEAR(c.x(), car.x, 0.01) << "t = " << t;
      EXPECT_NEAR(c.y(), car.y, 0.01) << "t = " << t;
    }
  }
  EXPECT_EQ(moving, 1);
  // The files round-trip and pass the schemas and the semantic checks.
  const std::string mj = missionJson(s.mission), sj = simConfigJson(s.sim);
  EXPECT_EQ(missionJson(parseMission(mj, "mission.json")), mj);
  EXPECT_EQ(simConfigJson(parseSimConfig(sj, "sim_config.json")), sj);
  EXPECT_TRUE(schemaIssues(mj, "mission.json").empty());
  EXPECT_TRUE(schemaIssues(sj, "sim_config.json").empty());
}

}  // namespace

TEST(AvoidGeneratorTest, SuburbScenariosAreWellPosed) {
  int n = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const Scenario s =
        generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kAvoid, seed);
    expectWellPosed(shippedWorld(), s);
    ++n;
  }
  EXPECT_EQ(n, 6);
}

TEST(AvoidGeneratorTest, CityScenariosAreWellPosed) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const Scenario s = generateScenario(cityWorld(), shippedConfig(), ScenarioClass::kAvoid, seed);
    expectWellPosed(cityWorld(), s);
  }
  // Every scenario of a 40-scenario city batch generates: among tall buildings the aircraft
  // fall back to shorter chords and head-on legs (indices 2 and 38 once found no room).
  int generated = 0;
  for (std::uint64_t i = 0; i < 40; ++i) {
    const std::uint64_t seed = batchSeed(1, i);
    try {
      generateScenario(cityWorld(), shippedConfig(), ScenarioClass::kAvoid, seed);
      ++generated;
    } catch (const GenerationError& e) {
      ADD_FAILURE() << e.what();
    }
  }
  EXPECT_EQ(generated, 40);
  // Two scenarios of a 3,000-scenario city batch (--seed 2026) whose orbiting aircraft found no
  // room for a lap among the towers, and a batch stopped there: such a slot crosses instead,
  // the second on the reference flight's longest leg 10 m above the first aircraft's head-on.
  for (const std::uint64_t seed : {618711239684142679ULL, 7283260579867774453ULL}) {
    try {
      expectWellPosed(cityWorld(),
                      generateScenario(cityWorld(), shippedConfig(), ScenarioClass::kAvoid, seed));
    } catch (const GenerationError& e) {
      ADD_FAILURE() << "seed " << seed << ": " << e.what();
    }
  }
}

TEST(AvoidGeneratorTest, SameSeedSameBytesOtherSeedOtherScenario) {
  const Scenario a = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kAvoid, 11);
  const Scenario b = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kAvoid, 11);
  const Scenario c = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kAvoid, 12);
  EXPECT_EQ(missionJson(a.mission), missionJson(b.mission));
  EXPECT_EQ(simConfigJson(a.sim), simConfigJson(b.sim));
  EXPECT_NE(simConfigJson(a.sim), simConfigJson(c.sim));  // control: the seed matters
}

// Negative controls: each doctored scenario is caught, at the field it breaks.
TEST(AvoidGeneratorTest, CheckCatchesDoctoredScenarios) {
  const World& w = shippedWorld();
  const Scenario s = generateScenario(w, shippedConfig(), ScenarioClass::kAvoid, 3);
  ASSERT_TRUE(checkAvoidScenario(w, s.mission, s.sim).empty());

  Scenario d = s;  // the UAV starts inside a house
  for (const auto& e : w.entities()) {
    if (e.cls == EntityClass::kHouse) {
      d.sim.uav.start.x = e.box.center.x();
      d.sim.uav.start.y = e.box.center.y();
      break;
    }
  }
  EXPECT_TRUE(mentions(checkAvoidScenario(w, d.mission, d.sim), "uav.start: inside an obstacle"));

  d = s;  // an aircraft jumps 500 m in one second
  d.sim.aircraft[0].trajectory[1].x += 500.0;
  d.sim.aircraft[0].trajectory[1].t = d.sim.aircraft[0].trajectory[0].t + 1.0;
  EXPECT_TRUE(mentions(checkAvoidScenario(w, d.mission, d.sim), "not continuous"));

  d = s;  // an aircraft waits on the UAV's start
  d.sim.aircraft[1].trajectory[0].x = d.sim.uav.start.x;
  d.sim.aircraft[1].trajectory[0].y = d.sim.uav.start.y;
  d.sim.aircraft[1].trajectory[0].z = 1.0;
  EXPECT_TRUE(mentions(checkAvoidScenario(w, d.mission, d.sim), "separation minimum"));

  d = s;  // a shortest path shorter than the straight line
  for (auto& p : d.mission.phases) p.avoid.shortest_path_m *= 0.5;
  EXPECT_TRUE(mentions(checkAvoidScenario(w, d.mission, d.sim), "shorter than the straight line"));

  d = s;  // a shortest path 10 % longer than the flight found
  for (auto& p : d.mission.phases) p.avoid.shortest_path_m *= 1.1;
  EXPECT_TRUE(mentions(checkAvoidScenario(w, d.mission, d.sim), "the shortest flight found"));

  d = s;  // the goal walled in by a zone over the whole band
  {
    KeepOutZone k;
    k.id = "koz_wall";
    k.purpose = "restricted";
    const Vec3 g = avoidSpec(s).goal;
    k.polygon = hameritt::geometry::orientedRectangle(Vec2(g.x(), g.y()), 12.0, 12.0, 0.0);
    d.mission.kozs.push_back(k);
  }
  EXPECT_TRUE(mentions(checkAvoidScenario(w, d.mission, d.sim), "unreachable"));

  d = s;  // no avoid phase
  d.mission.phases.clear();
  EXPECT_TRUE(mentions(checkAvoidScenario(w, d.mission, d.sim), "no avoid phase"));
}

// The semantic validator: an aircraft trajectory that jumps, an avoid mission without an avoid
// phase, an aircraft id that repeats an entity's.
TEST(AvoidGeneratorTest, ValidatorRulesCatchDoctoredFiles) {
  const Scenario s = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kAvoid, 4);
  auto rules = [](const std::vector<ValidationIssue>& v) {
    std::string out;
    for (const auto& i : v) out += i.rule + " " + i.path + "; ";
    return out;
  };
  nlohmann::json sim = nlohmann::json::parse(simConfigJson(s.sim));
  ASSERT_TRUE(schemaIssues(sim.dump(), "sim_config.json").empty());
  sim["aircraft"][0]["trajectory"][1][1] =
      sim["aircraft"][0]["trajectory"][1][1].get<double>() + 5000.0;
  EXPECT_NE(rules(schemaIssues(sim.dump(), "s")).find("trajectory_speed /aircraft/0/trajectory/1"),
            std::string::npos)
      << rules(schemaIssues(sim.dump(), "s"));
  sim = nlohmann::json::parse(simConfigJson(s.sim));
  sim["aircraft"][1]["id"] = sim["entities"][0]["id"];
  EXPECT_NE(rules(schemaIssues(sim.dump(), "s")).find("unique_id /aircraft/1"), std::string::npos)
      << rules(schemaIssues(sim.dump(), "s"));
  nlohmann::json m = nlohmann::json::parse(missionJson(s.mission));
  ASSERT_TRUE(schemaIssues(m.dump(), "mission.json").empty());
  m.erase("phases");
  EXPECT_NE(rules(schemaIssues(m.dump(), "m")).find("avoid_phase /phases"), std::string::npos)
      << rules(schemaIssues(m.dump(), "m"));
  m = nlohmann::json::parse(missionJson(s.mission));
  for (auto& k : m["keep_out_zones"]) {
    if (k.contains("motion")) k["motion"][1][0] = 0.0;  // time goes back
  }
  EXPECT_NE(rules(schemaIssues(m.dump(), "m")).find("trajectory_order"), std::string::npos)
      << rules(schemaIssues(m.dump(), "m"));
}

// The reference flight: straight where nothing blocks it; around a zone that walls off the
// direct line, longer than the line and clear of the zone (the straight line is not: control).
TEST(AvoidGeneratorTest, ShortestFlightGoesAroundAWall) {
  const World& w = shippedWorld();
  const Scenario s = generateScenario(w, shippedConfig(), ScenarioClass::kAvoid, 5);
  const auto vs = hameritt::planning::validitySettingsFor(s.sim.uav);
  const Vec3 start(s.sim.uav.start.x, s.sim.uav.start.y, 0.0);
  const Vec3 goal = avoidSpec(s).goal;
  const hameritt::planning::WorldValidity open(w, std::vector<KeepOutZone>{}, vs);
  const ReferenceFlight f = shortestFlight(open, start, goal);
  ASSERT_TRUE(f.ok) << f.why;
  const Vec3 up(start.x(), start.y(), vs.altitude_min);
  const Vec3 down = goal.z() < vs.altitude_min ? Vec3(goal.x(), goal.y(), vs.altitude_min) : goal;
  const double direct = up.z() + (down - up).norm() + (goal - down).norm();
  if (open.staticSegmentValid(up, down)) {
    EXPECT_NEAR(f.length, direct, 1e-6);
  }
  EXPECT_GE(f.length, direct - 1e-6);

  KeepOutZone wall;
  wall.id = "wall";
  wall.purpose = "restricted";
  const Vec2 mid(0.5 * (start.x() + goal.x()), 0.5 * (start.y() + goal.y()));
  const double yaw = std::atan2(goal.y() - start.y(), goal.x() - start.x()) + 0.5 * M_PI;
  wall.polygon = hameritt::geometry::orientedRectangle(mid, 120.0, 10.0, yaw);
  const hameritt::planning::WorldValidity walled(w, std::vector<KeepOutZone>{wall}, vs);
  EXPECT_FALSE(walled.kozSegmentClearDuring(up, down, 0.0, 1e9));  // control
  const ReferenceFlight g = shortestFlight(walled, start, goal);
  ASSERT_TRUE(g.ok) << g.why;
  EXPECT_GT(g.length, f.length + 1.0);
  // Around a 120 m wall: no longer than the detour over either end (plus the grid's slack).
  const double half = 60.0 + 2.0;
  const double detour =
      up.z() + 2.0 * std::hypot(0.5 * (down - up).head<2>().norm(), half) + (goal - down).norm();
  EXPECT_LE(g.length, detour * 1.03);
  for (std::size_t i = 1; i < g.path.size(); ++i) {
    EXPECT_TRUE(walled.kozSegmentClearDuring(g.path[i - 1], g.path[i], 0.0, 1e9)) << i;
  }
}

// A crossing aircraft passes its crossing point at the stated time, at its speed, and flies
// until the end; an orbit keeps its radius.
TEST(AvoidGeneratorTest, AircraftPatternsAreContinuous) {
  AircraftPattern p;
  p.a = Vec3(0, 0, 30);
  p.b = Vec3(200, 0, 36);
  p.cross = Vec3(80, 0, 32.4);
  p.t_cross = 20.0;
  p.speed = 12.0;
  const Trajectory t = aircraftTrajectory(p, 180.0);
  EXPECT_EQ(t.front().t, 0.0);
  EXPECT_EQ(t.back().t, 180.0);
  const TrajectoryPoint c = sampleTrajectory(t, 20.0);
  EXPECT_NEAR(c.x, 80.0, 0.02);
  EXPECT_NEAR(c.z, 32.4, 0.02);
  int reversals = 0;
  for (std::size_t i = 1; i < t.size(); ++i) {
    const double d = std::hypot(t[i].x - t[i - 1].x, t[i].y - t[i - 1].y, t[i].z - t[i - 1].z);
    EXPECT_LE(d / (t[i].t - t[i - 1].t), 12.0 * 1.01) << i;
    EXPECT_GE(t[i].x, -0.001);
    EXPECT_LE(t[i].x, 200.001);
    if (t[i].x == 0.0 || t[i].x == 200.0) ++reversals;
  }
  // 180 s at 12 m/s: from x = 160 back to a (t = 13.3 s), then 9 more ends of the 200.09 m chord.
  EXPECT_EQ(reversals, 10);

  AircraftPattern o;
  o.kind = AircraftPattern::Kind::kOrbit;
  o.centre = Vec3(10, 20, 40);
  o.radius = 40.0;
  o.speed = 8.0;
  const Trajectory r = aircraftTrajectory(o, 100.0);
  for (const auto& q : r) EXPECT_NEAR(std::hypot(q.x - 10, q.y - 20), 40.0, 0.01);
  EXPECT_EQ(r.back().t, 100.0);
}
