// The track class: pursuit's scene with one or two moving targets in two phases (search, then
// track) whose criteria and duration come from config/generator.json; the files validate (schema
// and semantic rules), round-trip, are deterministic; the second target drives the first one's
// streets without touching it; the routes pass occluders; the pursuit class is unchanged by it;
// and the track_phase rule catches doctored missions (the negative controls).
#include <gtest/gtest.h>

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

const ScenarioEntity* entity(const Scenario& s, const std::string& id) {
  for (const auto& e : s.sim.entities) {
    if (e.entity.id == id) return &e;
  }
  return nullptr;
}

// Occluders (street trees, buildings, houses, garages) whose centre comes within `radius` m of
// the target's driven path (sampled every second after it starts moving).
int occludersPassed(const World& w, const Trajectory& traj, double radius) {
  int n = 0;
  for (const auto& e : w.entities()) {
    if (e.cls != EntityClass::kStreetTree && e.cls != EntityClass::kBuilding &&
        e.cls != EntityClass::kHouse && e.cls != EntityClass::kGarage) {
      continue;
    }
    for (double t = traj[1].t; t <= traj.back().t; t += 1.0) {
      const TrajectoryPoint p = sampleTrajectory(traj, t);
      if ((e.box.center2() - hameritt::geometry::Vec2(p.x, p.y)).norm() < radius) {
        ++n;
        break;
      }
    }
  }
  return n;
}

// Checks one track scenario; returns its number of targets.
std::size_t expectWellPosed(const World& w, const Scenario& s) {
  SCOPED_TRACE(s.mission.scenario_id);
  const GeneratorConfig& c = shippedConfig();
  EXPECT_EQ(s.mission.scenario_id.rfind("track-", 0), 0u);
  EXPECT_EQ(s.mission.objective.type, "track");
  const auto& targets = s.mission.objective.targets;
  EXPECT_GE(targets.size(), 1u);
  EXPECT_LE(targets.size(), 2u);
  std::vector<std::string> ids;
  for (const auto& t : targets) ids.push_back(t.id);
  EXPECT_EQ(s.mission.phases.size(), 2u);
  if (s.mission.phases.size() != 2) return 0;
  const MissionPhase& search = s.mission.phases[0];
  const MissionPhase& track = s.mission.phases[1];
  EXPECT_EQ(search.type, PhaseType::kSearch);
  EXPECT_EQ(track.type, PhaseType::kTrack);
  EXPECT_EQ(search.targets, ids);
  EXPECT_EQ(track.targets, ids);
  EXPECT_TRUE(track.duration.has_value());
  const double duration = track.duration.value_or(0.0);
  EXPECT_GE(duration, std::round(c.track_duration.min));
  EXPECT_LE(duration, std::round(c.track_duration.max));
  EXPECT_DOUBLE_EQ(track.track.min_visible_fraction, 0.5);
  EXPECT_DOUBLE_EQ(track.track.min_box_area, 400.0);
  EXPECT_DOUBLE_EQ(track.track.min_tracked_fraction, 0.7);
  EXPECT_DOUBLE_EQ(track.track.max_reacquire_s, 10.0);
  EXPECT_GE(s.mission.time_limit, c.time_limit_pursuit.min + duration - 1.0);
  // Every target drives, past occluders; two targets never come within 4 m of each other.
  std::vector<const Trajectory*> trajs;
  for (const auto& id : ids) {
    const ScenarioEntity* e = entity(s, id);
    EXPECT_NE(e, nullptr) << id;
    if (!e) return 0;
    EXPECT_EQ(e->role, "target");
    EXPECT_GT(e->trajectory.size(), 2u) << id;
    if (e->trajectory.size() <= 2) return 0;
    EXPECT_GE(occludersPassed(w, e->trajectory, 15.0), 1) << id;
    trajs.push_back(&e->trajectory);
  }
  if (trajs.size() == 2) {
    double closest = 1e9;
    for (double t = 0; t <= trajs[0]->back().t; t += 0.25) {
      const TrajectoryPoint a = sampleTrajectory(*trajs[0], t), b = sampleTrajectory(*trajs[1], t);
      closest = std::min(closest, std::hypot(a.x - b.x, a.y - b.y));
    }
    EXPECT_GT(closest, 4.0);
    // Both stop where their routes end, 12 m apart on the same street.
    const auto &ea = trajs[0]->back(), &eb = trajs[1]->back();
    EXPECT_NEAR(std::hypot(ea.x - eb.x, ea.y - eb.y), 12.0, 1.0);
  }
  // Look-alike confusers of the first target: parked cars of its model and colour.
  int confusers = 0;
  for (const auto& e : s.sim.entities) {
    if (e.role == "confuser" && e.entity.cls == EntityClass::kCar &&
        e.entity.attributes.str("color") == targets[0].color &&
        e.entity.attributes.str("model") == targets[0].model) {
      ++confusers;
    }
  }
  EXPECT_GE(confusers, 1);
  expectValidAndRoundTrips(s);
  return targets.size();
}

TEST(TrackGeneratorTest, ScenariosAreWellPosedWithOneOrTwoTargets) {
  std::map<std::size_t, int> by_count;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    ++by_count[expectWellPosed(shippedWorld(), generateScenario(shippedWorld(), shippedConfig(),
                                                                ScenarioClass::kTrack, seed))];
  }
  EXPECT_GE(by_count[1], 1);
  EXPECT_GE(by_count[2], 1);
  EXPECT_EQ(by_count[1] + by_count[2], 6);
  // Two targets asked for: every scenario whose convoy route exists has them.
  GeneratorConfig two = shippedConfig();
  two.track_targets_min = 2;
  int with_two = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    with_two += expectWellPosed(shippedWorld(), generateScenario(shippedWorld(), two,
                                                                 ScenarioClass::kTrack, seed)) == 2;
  }
  EXPECT_GE(with_two, 3);
  expectWellPosed(shippedCityWorld(),
                  generateScenario(shippedCityWorld(), shippedConfig(), ScenarioClass::kTrack, 1));
}

// The convoy's second car drives two seconds behind the first (the two-second rule) wherever
// both cruise the same streets, so one down camera can hold both: along the first car's route
// from 60 m past its pull-out to 30 m before its stop (the suburb: no signals part them), the
// second car passes each of its points 1.8-2.3 s later, and never comes nearer than half their
// lengths plus 0.5 m. (With the wait's 22 m and a departure 2.5 s after the pull-out the gap
// was about 4.9 s, 44 m at 9 m/s: seen failing.)
TEST(TrackGeneratorTest, TheConvoysSecondCarDrivesTwoSecondsBehind) {
  GeneratorConfig two = shippedConfig();
  two.track_targets_min = 2;
  int convoys = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const Scenario s = generateScenario(shippedWorld(), two, ScenarioClass::kTrack, seed);
    SCOPED_TRACE(s.mission.scenario_id);
    if (s.mission.objective.targets.size() != 2) continue;
    ++convoys;
    const ScenarioEntity* lead = entity(s, s.mission.objective.targets[0].id);
    const ScenarioEntity* second = entity(s, s.mission.objective.targets[1].id);
    ASSERT_TRUE(lead && second);
    const Trajectory &a = lead->trajectory, &b = second->trajectory;
    ASSERT_GT(a.size(), 12u);
    std::vector<double> arc(a.size(), 0.0);
    for (std::size_t i = 12; i < a.size(); ++i) {
      arc[i] = arc[i - 1] + std::hypot(a[i].x - a[i - 1].x, a[i].y - a[i - 1].y);
    }
    double lo = 1e9, hi = -1e9;
    for (std::size_t i = 12; i < a.size(); ++i) {
      if (arc[i] < 60.0 || arc[i] > arc.back() - 30.0) continue;
      // When the second car passes closest to the first car's point i.
      double best = 1e9, when = 0.0;
      for (std::size_t j = 1; j < b.size(); ++j) {
        const double dx = b[j].x - b[j - 1].x, dy = b[j].y - b[j - 1].y;
        const double len2 = dx * dx + dy * dy;
        const double u = len2 > 1e-12 ? std::clamp(((a[i].x - b[j - 1].x) * dx +
                                                    (a[i].y - b[j - 1].y) * dy) / len2, 0.0, 1.0)
                                       : 0.0;
        const double d = std::hypot(b[j - 1].x + u * dx - a[i].x, b[j - 1].y + u * dy - a[i].y);
        if (d < best) best = d, when = b[j - 1].t + u * (b[j].t - b[j - 1].t);
      }
      EXPECT_LT(best, 0.5) << "point " << i << ": the second car leaves the first one's path";
      lo = std::min(lo, when - a[i].t);
      hi = std::max(hi, when - a[i].t);
    }
    EXPECT_GE(lo, 1.8);
    EXPECT_LE(hi, 2.3);
    const double reach = 0.5 * (lead->entity.box.size.x() + second->entity.box.size.x()) + 0.5;
    double closest = 1e9;
    for (double t = 0; t <= a.back().t; t += 0.1) {
      const TrajectoryPoint p = sampleTrajectory(a, t), q = sampleTrajectory(b, t);
      closest = std::min(closest, std::hypot(p.x - q.x, p.y - q.y));
    }
    EXPECT_GE(closest, reach);
  }
  EXPECT_GE(convoys, 4);
}

// The search phase is feasible: the target waits 50-80 s (its area's window), and the UAV starts
// near enough to arrive 30 s before it drives off even at top speed, within max(240 m, 60 % of
// the top speed x (departure - 30 s)). (With pursuit's 20-60 s wait and a start up to 600 m
// away, 11 of the 14 searches that failed in 45 lock-step missions could reach no cell of the
// area inside its window: seen failing with pursuit's timing.)
TEST(TrackGeneratorTest, TheUavCanReachTheTargetBeforeItDeparts) {
  for (const World* w : {&shippedWorld(), &shippedCityWorld()}) {
    for (std::uint64_t i = 0; i < 12; ++i) {
      const Scenario s =
          generateScenario(*w, shippedConfig(), ScenarioClass::kTrack, batchSeed(3, i));
      ASSERT_FALSE(s.mission.aois.empty());
      ASSERT_TRUE(s.mission.aois[0].window.nlt.has_value());
      const double depart = *s.mission.aois[0].window.nlt;
      EXPECT_GE(depart, 50.0);
      EXPECT_LE(depart, 80.0);
      const ScenarioEntity* target = entity(s, s.mission.objective.targets.at(0).id);
      ASSERT_NE(target, nullptr);
      // Standing at the kerb until the departure.
      const TrajectoryPoint a = sampleTrajectory(target->trajectory, 0.0);
      const TrajectoryPoint b = sampleTrajectory(target->trajectory, depart);
      EXPECT_LT(std::hypot(a.x - b.x, a.y - b.y), 1e-6);
      const double d = std::hypot(s.sim.uav.start.x - a.x, s.sim.uav.start.y - a.y);
      EXPECT_LE(d, std::max(240.0, 0.6 * s.sim.uav.max_speed * (depart - 30.0)) + 1.0);
      EXPECT_LE(d / s.sim.uav.max_speed, depart - 30.0 + 0.1) << "seed index " << i;
    }
  }
}

TEST(TrackGeneratorTest, DeterministicAndPursuitUnchanged) {
  // The track scene is pursuit's with the same seed: the first target, its look and its route.
  const auto [a, p] = expectDeterministicOverPursuit(ScenarioClass::kTrack, 7);
  ASSERT_FALSE(p.mission.objective.targets.empty());
  const ScenarioEntity* pt = entity(p, p.mission.objective.targets[0].id);
  const ScenarioEntity* at = entity(a, a.mission.objective.targets[0].id);
  ASSERT_TRUE(pt && at);
  EXPECT_EQ(pt->trajectory.size(), at->trajectory.size());
  EXPECT_DOUBLE_EQ(a.mission.time_limit, p.mission.time_limit + *a.mission.phases[1].duration);
}

TEST(TrackGeneratorTest, TrackPhaseRuleCatchesDoctoredMissions) {
  const Scenario s = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kTrack, 4);
  const nlohmann::json good = nlohmann::json::parse(missionJson(s.mission));
  ASSERT_TRUE(issues(good).empty()) << rules(issues(good));
  nlohmann::json m = good;
  m["phases"].erase(1);  // the track phase gone
  EXPECT_NE(rules(issues(m)).find("track_phase /phases"), std::string::npos) << rules(issues(m));
  m = good;
  m["phases"][1]["targets"] = nlohmann::json::array({m["phases"][0]["targets"][0]});
  m["phases"][0]["targets"].push_back("car_9999");  // the search looks for another target
  EXPECT_NE(rules(issues(m)).find("track_phase /phases/1/targets"), std::string::npos)
      << rules(issues(m));
  m = good;
  m["phases"][1]["duration"] = m["time_limit"].get<double>() + 1.0;
  EXPECT_NE(rules(issues(m)).find("track_phase /phases/1/duration"), std::string::npos)
      << rules(issues(m));
  m = good;
  m["phases"][1]["type"] = "follow";  // a follow phase in a track mission
  EXPECT_NE(rules(issues(m)).find("track_phase /phases"), std::string::npos) << rules(issues(m));
}

TEST(TrackGeneratorTest, ConfigRangesAreChecked) {
  GeneratorConfig c = shippedConfig();
  c.track_targets_max = 3;
  EXPECT_NE(messageOf([&] { c.validate(); }).find("generator.track_targets_min/track_targets_max"),
            std::string::npos);
  c = shippedConfig();
  c.track_duration = {5, 60};
  EXPECT_NE(messageOf([&] { c.validate(); }).find("generator.track_duration"), std::string::npos);
  c = shippedConfig();
  c.track_min_visible_fraction = 1.5;
  EXPECT_NE(messageOf([&] { c.validate(); }).find("track_min_visible_fraction"), std::string::npos);
  c = shippedConfig();
  c.track_depart_time = {5, 60};
  EXPECT_NE(messageOf([&] { c.validate(); }).find("generator.track_depart_time"),
            std::string::npos);
  c = shippedConfig();
  EXPECT_EQ(messageOf([&] { c.validate(); }), "(no error)");
}

}  // namespace
