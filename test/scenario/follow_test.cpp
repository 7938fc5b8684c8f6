// The follow class: pursuit's moving target in two phases (search, then follow) whose envelope
// and duration come from config/generator.json's ranges; the files validate (schema and
// semantic rules), round-trip, are deterministic; the pursuit class is unchanged by it; and the
// follow_phase rule catches doctored missions (the negative controls).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/validation.h"
#include "test_util.h"
#include "validation_test_util.h"

using namespace hameritt::scenario;
using namespace hameritt::scenario::testing;

namespace {

bool within(double v, const Range& r) { return v >= std::round(r.min) && v <= std::round(r.max); }

void expectWellPosed(const Scenario& s) {
  SCOPED_TRACE(s.mission.scenario_id);
  const GeneratorConfig& c = shippedConfig();
  EXPECT_EQ(s.mission.scenario_id.rfind("follow-", 0), 0u);
  EXPECT_EQ(s.mission.objective.type, "track");
  ASSERT_EQ(s.mission.objective.targets.size(), 1u);
  const std::string target = s.mission.objective.targets[0].id;
  ASSERT_EQ(s.mission.phases.size(), 2u);
  const MissionPhase& search = s.mission.phases[0];
  const MissionPhase& follow = s.mission.phases[1];
  EXPECT_EQ(search.type, PhaseType::kSearch);
  EXPECT_EQ(follow.type, PhaseType::kFollow);
  EXPECT_EQ(search.targets, std::vector<std::string>{target});
  EXPECT_EQ(follow.targets, std::vector<std::string>{target});
  ASSERT_TRUE(follow.duration.has_value());
  EXPECT_TRUE(within(*follow.duration, c.follow_duration)) << *follow.duration;
  const FollowPhaseSpec& f = follow.follow;
  EXPECT_TRUE(within(f.distance, c.follow_distance)) << f.distance;
  EXPECT_TRUE(within(f.distance_tolerance, c.follow_distance_tolerance));
  EXPECT_TRUE(within(f.height_tolerance, c.follow_height_tolerance));
  // h* +- H inside the UAV's altitude band.
  EXPECT_GE(f.height - f.height_tolerance, s.sim.uav.altitude_min - 1e-9);
  EXPECT_LE(f.height + f.height_tolerance, s.sim.uav.altitude_max + 1e-9);
  EXPECT_DOUBLE_EQ(f.min_inside_fraction, 0.8);
  EXPECT_DOUBLE_EQ(f.max_outside_s, 10.0);
  // The approach allowance: 200 m closed at half the UAV's top speed, within [10, 60] s.
  EXPECT_DOUBLE_EQ(f.approach_s,
                   std::clamp(std::ceil(200.0 / (0.5 * s.sim.uav.max_speed)), 10.0, 60.0));
  // The time limit leaves the search pursuit's time, the approach and the whole follow phase.
  EXPECT_GE(s.mission.time_limit, c.time_limit_pursuit.min + f.approach_s + *follow.duration - 1.0);
  // The target drives (a trajectory with more than the waiting samples).
  bool moving = false;
  for (const auto& e : s.sim.entities) {
    if (e.entity.id == target) moving = e.trajectory.size() > 2;
  }
  EXPECT_TRUE(moving);
  expectValidAndRoundTrips(s);
}

TEST(FollowGeneratorTest, ScenariosAreWellPosedInTheSuburbAndTheCity) {
  for (std::uint64_t seed : {1, 2, 3}) {
    expectWellPosed(
        generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kFollow, seed));
  }
  expectWellPosed(generateScenario(shippedCityWorld(), shippedConfig(), ScenarioClass::kFollow, 1));
}

TEST(FollowGeneratorTest, DeterministicAndPursuitUnchanged) {
  // The follow scene is pursuit's with the same seed: the target and its look (its route too,
  // driven no faster than the cap of TargetsNeverOutrunTheUav).
  const auto [a, p] = expectDeterministicOverPursuit(ScenarioClass::kFollow, 7);
  EXPECT_DOUBLE_EQ(
      a.mission.time_limit,
      p.mission.time_limit + a.mission.phases[1].follow.approach_s + *a.mission.phases[1].duration);
}

// The fastest a trajectory moves over any stretch of at least 1 s (positions are rounded to the
// millimetre: over a second that is at most 2 mm/s of error).
double topSpeed(const Trajectory& tr) {
  double top = 0.0;
  for (std::size_t i = 0; i < tr.size(); ++i) {
    double run = 0.0;
    for (std::size_t j = i + 1; j < tr.size(); ++j) {
      run += std::hypot(tr[j].x - tr[j - 1].x, tr[j].y - tr[j - 1].y);
      if (tr[j].t - tr[i].t >= 1.0) {
        top = std::max(top, run / (tr[j].t - tr[i].t));
        break;
      }
    }
  }
  return top;
}

// Follow and track targets drive no faster than 0.75 of the UAV's top speed (a follower must
// gain on them); the pursuit targets of the same seeds, drawn from car_speed up to 13 m/s, are
// the control that the measure finds a faster car.
TEST(FollowGeneratorTest, TargetsNeverOutrunTheUav) {
  double fastest_pursuit = 0.0;
  for (const auto cls : {ScenarioClass::kFollow, ScenarioClass::kTrack, ScenarioClass::kPursuit}) {
    double fastest = 0.0;
    int targets = 0;
    for (std::uint64_t seed = 1; seed <= 12; ++seed) {
      const Scenario s = generateScenario(shippedWorld(), shippedConfig(), cls, seed);
      const double cap = 0.75 * s.sim.uav.max_speed;
      for (const auto& t : s.mission.objective.targets) {
        for (const auto& e : s.sim.entities) {
          if (e.entity.id != t.id) continue;
          const double v = topSpeed(e.trajectory);
          fastest = std::max(fastest, v);
          ++targets;
          if (cls != ScenarioClass::kPursuit) {
            EXPECT_LE(v, cap + 0.05) << s.mission.scenario_id << " " << t.id;
          }
        }
      }
    }
    std::printf("%s: %d targets of seeds 1-12, fastest %.2f m/s over a second\n", toString(cls),
                targets, fastest);
    EXPECT_GE(targets, 12);
    if (cls == ScenarioClass::kPursuit) fastest_pursuit = fastest;
  }
  EXPECT_GT(fastest_pursuit, 0.75 * shippedConfig().uav_max_speed + 0.5);
}

TEST(FollowGeneratorTest, FollowPhaseRuleCatchesDoctoredMissions) {
  const Scenario s = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kFollow, 4);
  const nlohmann::json good = nlohmann::json::parse(missionJson(s.mission));
  ASSERT_TRUE(issues(good).empty()) << rules(issues(good));
  nlohmann::json m = good;
  m["phases"].erase(1);  // the follow phase gone
  EXPECT_NE(rules(issues(m)).find("follow_phase /phases"), std::string::npos) << rules(issues(m));
  m = good;
  m["phases"][1]["targets"][0] = "car_9999";  // another target than the search's
  EXPECT_NE(rules(issues(m)).find("follow_phase /phases/1/targets"), std::string::npos)
      << rules(issues(m));
  m = good;
  m["phases"][1]["duration"] = m["time_limit"].get<double>() + 1.0;
  EXPECT_NE(rules(issues(m)).find("follow_phase /phases/1/duration"), std::string::npos)
      << rules(issues(m));
  // A duration that fits the limit only without the approach allowance.
  m = good;
  m["phases"][1]["duration"] = m["time_limit"].get<double>() - 1.0;
  ASSERT_GT(m["phases"][1]["criteria"]["approach_s"].get<double>(), 1.0);
  EXPECT_NE(rules(issues(m)).find("follow_phase /phases/1/duration"), std::string::npos)
      << rules(issues(m));
  m = good;
  m.erase("phases");
  EXPECT_NE(rules(issues(m)).find("follow_phase /phases"), std::string::npos) << rules(issues(m));
}

TEST(FollowGeneratorTest, ConfigRangesAreChecked) {
  GeneratorConfig c = shippedConfig();
  c.follow_height_tolerance = {5, 9};  // 18 m does not fit a 15 m band
  EXPECT_NE(messageOf([&] { c.validate(); }).find("generator.follow_height_tolerance"),
            std::string::npos);
  c = shippedConfig();
  c.follow_duration = {5, 60};
  EXPECT_NE(messageOf([&] { c.validate(); }).find("follow_duration"), std::string::npos);
  c = shippedConfig();
  EXPECT_EQ(messageOf([&] { c.validate(); }), "(no error)");
}

}  // namespace
