#include "hameritt/adk/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "../scenario/test_util.h"
#include "adk_test_util.h"
#include "hameritt/scenario/error.h"

namespace hameritt::adk {
namespace {

using namespace testing;  // NOLINT

TEST(EnergyModel, HoverPowerFromMomentumTheory) {
  const EnergyModel e;
  // T = 1.04 * 9.81 N over 4 disks of radius 0.0635 m: T^1.5 / sqrt(2 rho A) / FM.
  const double T = 1.04 * 9.81, A = 4 * geometry::kPi * 0.0635 * 0.0635;
  EXPECT_NEAR(e.hoverPower(), std::pow(T, 1.5) / std::sqrt(2 * 1.225 * A) / 0.6, 1e-9);
  EXPECT_NEAR(e.hoverPower(), 154.15, 0.05);
  // Climbing at 1 g needs 2^1.5 times the induced power; speed adds drag power.
  EXPECT_NEAR(e.power(Vec3::Zero(), Vec3(0, 0, 9.81)), e.hoverPower() * std::pow(2.0, 1.5), 1e-9);
  EXPECT_NEAR(e.power(Vec3(10, 0, 0), Vec3::Zero()) - e.hoverPower(), 0.5 * 1.225 * 0.02 * 1000,
              1e-9);
  // The thrust is capped at 3 m g: an acceleration of 100 g costs what 2 g up costs.
  EXPECT_NEAR(e.power(Vec3::Zero(), Vec3(0, 0, 981)), e.hoverPower() * std::pow(3.0, 1.5), 1e-9);
  EnergyModel bad;
  bad.figure_of_merit = 1.5;
  EXPECT_THROW(bad.validate(), scenario::ConfigError);
}

TEST(MetricsAccumulator, PathFlightTimeAndEnergy) {
  MetricsAccumulator acc(shippedMission());
  const EnergyModel e;
  // 2 s on the ground, 10 s hovering at 10 m (appearing there), 10 s at 5 m/s east.
  for (int i = 0; i <= 20; ++i) acc.addState(0.1 * i, Vec3(0, 0, 0.05), Vec3::Zero());
  for (int i = 0; i <= 100; ++i) acc.addState(2.0 + 0.1 * i + 1e-9, Vec3(0, 0, 10), Vec3::Zero());
  for (int i = 1; i <= 100; ++i) acc.addState(12.0 + 0.1 * i, Vec3(0.5 * i, 0, 10), Vec3(5, 0, 0));
  EXPECT_FALSE(acc.addState(5.0, Vec3(0, 0, 10), Vec3::Zero()));  // out of order: ignored
  const FlightMetrics& f = acc.flight();
  EXPECT_NEAR(f.path_length, 10.0 - 0.05 + 50.0, 1e-9);
  EXPECT_NEAR(f.flight_time, 20.0, 1e-6);
  EXPECT_DOUBLE_EQ(f.max_speed, 5.0);
  // The jump to 10 m takes 1 ns; the step to 5 m/s is one period at the acceleration
  // 50 m/s^2 and the mean speed 2.5 m/s; every other period is steady.
  const double steady = 10.0 * e.hoverPower() + 9.9 * e.power(Vec3(5, 0, 0), Vec3::Zero());
  const double step = 0.1 * e.power(Vec3(2.5, 0, 0), Vec3(50, 0, 0));
  EXPECT_NEAR(f.energy, steady + step, 1e-3);
  EXPECT_THROW(acc.addState(30, Vec3(0, 0, std::nan("")), Vec3::Zero()), InputError);
}

DetectionVerdict verdict(Verdict v, const std::string& id) {
  DetectionVerdict d;
  d.verdict = v;
  d.entity_id = id;
  return d;
}

TEST(MetricsAccumulator, DetectionsSightingsAndTheFindObjective) {
  MetricsAccumulator acc(shippedMission());
  EXPECT_FALSE(acc.isTrack());
  EXPECT_FALSE(acc.objectiveMet(10));
  acc.addVerdict(12.0, verdict(Verdict::kConfuser, "car_721"));
  acc.addVerdict(13.0, verdict(Verdict::kNone, ""));
  acc.addVerdict(14.0, verdict(Verdict::kOther, "car_5"));
  acc.addSighting("car_706", 15.0, 0.1);
  EXPECT_FALSE(acc.objectiveMet(15));  // seen is not claimed
  acc.addVerdict(20.0, verdict(Verdict::kTarget, "car_706"));
  acc.addVerdict(18.0, verdict(Verdict::kTarget, "car_706"));  // earlier stamp, later arrival
  EXPECT_TRUE(acc.objectiveMet(21));
  acc.addSighting("car_706", 15.05, 0.1);
  acc.addSighting("car_721", 15.0, 0.1);  // not a target: no in-view time
  ConstraintMonitor mon(shippedMission());
  CoverageGrid cov(shippedMission());
  const MissionMetrics m =
      acc.finish(Outcome::kSuccess, "all targets found", 1.0, 21.0, 472, "end_to_end", mon, cov);
  ASSERT_EQ(m.targets.size(), 1u);
  EXPECT_TRUE(m.targets[0].found);
  EXPECT_EQ(*m.targets[0].first_correct_time, 18.0);
  EXPECT_EQ(*m.targets[0].first_seen_time, 15.0);
  EXPECT_NEAR(m.targets[0].in_view_time, 0.15, 1e-12);
  EXPECT_EQ(*m.time_to_first_correct, 18.0);
  EXPECT_EQ(*m.time_to_all_found, 18.0);
  EXPECT_EQ(m.detections.total, 5);
  EXPECT_EQ(m.detections.correct, 2);
  EXPECT_EQ(m.detections.false_on_confusers, 1);
  EXPECT_EQ(m.detections.false_on_other_entities, 1);
  EXPECT_EQ(m.detections.false_on_nothing, 1);
}

TEST(MetricsAccumulator, FoundBySightingAndTrackObjectives) {
  ObjectiveSettings by_sight;
  by_sight.found_by_sighting = true;
  MetricsAccumulator acc(shippedMission(), by_sight);
  acc.addSighting("car_706", 30.0, 0.1);
  EXPECT_TRUE(acc.objectiveMet(31));

  scenario::Mission track = shippedMission();
  track.objective.type = "track";
  MetricsAccumulator t(track);
  EXPECT_TRUE(t.isTrack());
  for (int i = 0; i < 40; ++i) t.addSighting("car_706", 0.1 * i, 0.1);  // 4 s in view
  EXPECT_TRUE(t.objectiveMet(8.0));
  EXPECT_FALSE(t.objectiveMet(8.1));
  EXPECT_FALSE(t.objectiveMet(0.0));
}

TEST(MetricsJson, StableFieldOrderNullsAndAtomicWrite) {
  MetricsAccumulator acc(shippedMission());
  acc.addState(1.0, Vec3(0, 0, 10), Vec3::Zero());
  acc.addState(2.0, Vec3(0, 0, 10), Vec3::Zero());
  ConstraintMonitor mon(shippedMission());
  mon.add(1.0, Vec3(-270, 240, 30));  // inside koz_1 and koz_2
  mon.add(2.0, Vec3(-200, 100, 30));
  CoverageGrid cov(shippedMission());
  const MissionMetrics m =
      acc.finish(Outcome::kTimeout, "time limit", 1.0, 2.0, 2.0, "maneuver_only", mon, cov);
  const std::string text = metricsJson(m);
  EXPECT_EQ(text, metricsJson(m));
  const auto j = nlohmann::ordered_json::parse(text);
  std::vector<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  EXPECT_EQ(keys, (std::vector<std::string>{
                      "schema", "schema_version", "scenario_id", "class", "objective_type", "mode",
                      "outcome", "reason", "start_time", "end_time", "time_limit", "targets",
                      "time_to_first_correct_detection", "time_to_all_targets_found", "detections",
                      "keep_out_zones", "flight", "coverage"}));
  EXPECT_EQ(j["outcome"], "timeout");
  EXPECT_TRUE(j["time_to_first_correct_detection"].is_null());
  EXPECT_TRUE(j["targets"][0]["first_seen_time"].is_null());
  EXPECT_EQ(j["keep_out_zones"]["violation_count"], 2);
  EXPECT_EQ(j["keep_out_zones"]["violations"][0]["zone"], "koz_1");
  EXPECT_EQ(j["keep_out_zones"]["violations"][0]["t_enter"], 1.0);
  EXPECT_NEAR(j["flight"]["energy"].get<double>(), EnergyModel().hoverPower(), 1e-9);
  EXPECT_EQ(j["coverage"]["areas_of_interest"].size(), 2u);
  EXPECT_EQ(j["coverage"]["areas_of_interest"][0]["entries"], 1);  // starts inside aoi_1
  EXPECT_EQ(j["coverage"]["areas_of_interest"][1]["entries"], 0);

  const std::string dir = scenario::testing::freshTempDir("metrics_json");
  writeMetricsJson(m, dir + "/metrics.json");
  std::ifstream f(dir + "/metrics.json");
  std::stringstream ss;
  ss << f.rdbuf();
  EXPECT_EQ(ss.str(), text);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir),
                          std::filesystem::directory_iterator()),
            1);  // no temporary left behind
  EXPECT_THROW(writeMetricsJson(m, dir + "/missing/metrics.json"), scenario::OutputError);
}

TEST(MissionLifecycle, Transitions) {
  MissionLifecycle l(10.0);
  EXPECT_EQ(l.state(), MissionState::kWaiting);
  EXPECT_FALSE(l.update(0.0, true));   // sim time 0 is not a start
  EXPECT_FALSE(l.update(1.0, false));  // no odometry yet
  EXPECT_TRUE(l.update(1.5, true));
  EXPECT_EQ(l.state(), MissionState::kRunning);
  EXPECT_EQ(l.startTime(), 1.5);
  EXPECT_FALSE(l.update(9.99, true));
  EXPECT_TRUE(l.update(10.0, true));
  EXPECT_EQ(l.state(), MissionState::kTimeout);
  EXPECT_TRUE(l.ended());
  EXPECT_EQ(l.endTime(), 10.0);
  EXPECT_FALSE(l.crash(11.0, "late"));  // ended stays ended
  EXPECT_EQ(l.state(), MissionState::kTimeout);
  EXPECT_EQ(outcomeOf(l.state()), Outcome::kTimeout);

  MissionLifecycle c(10.0);
  c.update(1.0, true);
  EXPECT_TRUE(c.crash(3.0, "crashed into house_3"));
  EXPECT_STREQ(toString(c.state()), "crashed");
  EXPECT_EQ(c.reason(), "crashed into house_3");
  MissionLifecycle a(10.0);
  EXPECT_TRUE(a.abort(0.0, "shut down"));
  EXPECT_EQ(outcomeOf(a.state()), Outcome::kAborted);
  MissionLifecycle s(10.0);
  s.update(1.0, true);
  EXPECT_TRUE(s.succeed(4.0, "found"));
  EXPECT_EQ(outcomeOf(s.state()), Outcome::kSuccess);
  MissionLifecycle e(10.0);
  e.update(1.0, true);
  EXPECT_TRUE(e.simulationEnded(8.0, "simulation duration 8 s reached"));
  EXPECT_EQ(outcomeOf(e.state()), Outcome::kEnded);
  EXPECT_STREQ(toString(e.state()), "ended");
  EXPECT_STREQ(toString(outcomeOf(e.state())), "ended");
  EXPECT_EQ(e.endTime(), 8.0);
  EXPECT_FALSE(e.update(10.0, true));  // ended stays ended: no timeout after it
  EXPECT_EQ(e.state(), MissionState::kEnded);
  EXPECT_THROW(MissionLifecycle(0.0), InputError);
  MissionLifecycle f(10.0);
  f.update(1.0, true);
  EXPECT_TRUE(f.fail(6.0, "reached the goal, but lost separation"));
  EXPECT_STREQ(toString(f.state()), "failed");
  EXPECT_STREQ(toString(outcomeOf(f.state())), "failed");
  EXPECT_FALSE(f.succeed(7.0, "late"));  // failed stays failed
  EXPECT_FALSE(f.update(10.0, true));
}

// An avoid mission's metrics.json carries the phase's score after the coverage, times that
// never happened as null; other missions have no "avoid" block (the test above lists keys).
TEST(MetricsJson, AvoidBlock) {
  scenario::AvoidPhaseSpec spec;
  spec.goal = Vec3(100, 0, 0);
  spec.goal_radius = 5.0;
  spec.shortest_path_m = 100.0;
  AvoidScorer scorer(spec, 60.0);
  for (int i = 0; i <= 20; ++i) {
    TrafficSample s;
    s.t = i;
    s.position = Vec3(5.0 * i, 0, 0);
    AircraftState a;
    a.id = "aircraft_1";
    a.position = Vec3(50, 4, 1);  // 4 m aside, 1 m up: a loss of separation at x = 50
    s.aircraft.push_back(a);
    scorer.add(s);
  }
  ASSERT_TRUE(scorer.reached());
  MetricsAccumulator acc(shippedMission());
  ConstraintMonitor mon(shippedMission());
  CoverageGrid cov(shippedMission());
  MissionMetrics m =
      acc.finish(Outcome::kFailed, "lost separation", 0.0, 19.0, 60.0, "maneuver_only", mon, cov);
  m.avoid = scorer.score(2.5);
  const auto j = nlohmann::ordered_json::parse(metricsJson(m));
  EXPECT_EQ(j["outcome"], "failed");
  std::vector<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  ASSERT_EQ(keys.back(), "avoid");
  const auto& a = j["avoid"];
  EXPECT_FALSE(a["success"].get<bool>());
  EXPECT_NE(a["failure"].get<std::string>().find("lost separation 1 time"), std::string::npos);
  EXPECT_EQ(a["reach_time"], 19.0);  // x = 95: within 5 m of the goal
  EXPECT_EQ(a["path_length"], 95.0);
  EXPECT_EQ(a["spl"], 0.0);
  EXPECT_NEAR(a["min_separation"].get<double>(), std::sqrt(17.0), 1e-9);
  EXPECT_EQ(a["closest_aircraft"], "aircraft_1");
  EXPECT_EQ(a["separation_losses"], 1);
  EXPECT_EQ(a["koz_seconds"], 2.5);
  EXPECT_FALSE(a["contact"].get<bool>());
  // Without aircraft the separation figures are null, not infinite (JSON has no infinity).
  AvoidScorer empty(spec, 60.0);
  empty.add(TrafficSample{});
  m.avoid = empty.score();
  const auto k = nlohmann::ordered_json::parse(metricsJson(m));
  EXPECT_TRUE(k["avoid"]["min_separation"].is_null());
  EXPECT_TRUE(k["avoid"]["min_time_to_collision"].is_null());
  EXPECT_TRUE(k["avoid"]["reach_time"].is_null());
}

TEST(MetricsJson, TrackBlock) {
  scenario::MissionPhase phase;
  phase.id = "track_1";
  phase.type = scenario::PhaseType::kTrack;
  phase.targets = {"car_1"};
  phase.duration = 2.0;
  TrackScorer scorer(phase);
  scorer.start(0.0);
  for (int i = 1; i <= 20; ++i) {
    const double t = 0.1 * i;
    scorer.addFrame(t, {{"car_1", PixelBox{10, 10, 40, 30}, 0.9, 0.1}});
    scorer.addReport(t, {{"car_1", PixelBox{10, 10, 40, 30}}, {"car_9", PixelBox{0, 0, 1, 1}}});
  }
  MetricsAccumulator acc(shippedMission());
  ConstraintMonitor mon(shippedMission());
  CoverageGrid cov(shippedMission());
  MissionMetrics m =
      acc.finish(Outcome::kSuccess, "tracked", 0.0, 2.0, 60.0, "maneuver_only", mon, cov);
  m.track = scorer.score(true);
  const auto j = nlohmann::ordered_json::parse(metricsJson(m));
  std::vector<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  ASSERT_EQ(keys.back(), "track");
  const auto& t = j["track"];
  EXPECT_TRUE(t["success"].get<bool>()) << t["failure"];
  EXPECT_EQ(t["state"], "succeeded");
  EXPECT_EQ(t["frames"], 20);
  EXPECT_EQ(t["reports"], 20);
  EXPECT_EQ(t["report_errors"]["unknown_id"], 20);
  EXPECT_EQ(t["report_errors"]["total"], 20);
  EXPECT_EQ(t["tracked_fraction"], 1.0);
  ASSERT_EQ(t["per_target"].size(), 1u);
  EXPECT_EQ(t["per_target"][0]["precision"], 1.0);
  EXPECT_EQ(t["per_target"][0]["by_occlusion"]["partial"]["frames"], 20);
  EXPECT_EQ(t["clear_mot"]["mota"], 1.0);
  EXPECT_EQ(t["identity"]["idf1"], 1.0);
  EXPECT_GT(t["hota"]["hota"].get<double>(), 0.9);
  // Control: without a track phase there is no block.
  m.track.reset();
  EXPECT_FALSE(nlohmann::ordered_json::parse(metricsJson(m)).contains("track"));
}

}  // namespace
}  // namespace hameritt::adk
