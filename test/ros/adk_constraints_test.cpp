// rostest: a flight published as odometry on sim time through an active keep-out zone is
// reported by the adk node with the exact entry time and the window's closing time; flights
// through a zone whose window has not opened are not; hameritt_check_path on the same samples
// written as CSV agrees with the node.
#include "hameritt/build_paths.h"
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "adk_test_client.h"
#include "hameritt/ConstraintEvent.h"
#include "hameritt/ConstraintStatus.h"
#include "hameritt/MissionState.h"
#include "hameritt/adk/path_csv.h"
#include "hameritt/scenario/mission_io.h"

using Eigen::Vector3d;

namespace {

// Piecewise-linear flight (legs at constant velocity), sampled at 20 Hz of sim time.
struct Leg {
  double t0, t1;
  Vector3d a, b;
};
const std::vector<Leg> kLegs = {
    // At 50 m along y = 250 through koz_1 (active 20..60 s in the test mission; 0..96 m).
    {0.0, 100.0, {-320, 250, 50}, {-220, 250, 50}},
    // Down to 20 m, then north through koz_2 (0..36 m; its window opens at 1000 s).
    {100.0, 110.0, {-220, 250, 50}, {-200, 230, 20}},
    {110.0, 130.0, {-200, 230, 20}, {-200, 270, 20}},
    // Hover.
    {130.0, 131.0, {-200, 270, 20}, {-200, 270, 20}},
};

Vector3d positionAt(double t, Vector3d* v) {
  for (const auto& l : kLegs) {
    if (t <= l.t1) {
      *v = (l.b - l.a) / (l.t1 - l.t0);
      return l.a + (l.b - l.a) * ((t - l.t0) / (l.t1 - l.t0));
    }
  }
  *v = Vector3d::Zero();
  return kLegs.back().b;
}

// Entry and exit times of the first leg in the polygon by bisection on Polygon::contains
// (independent of the monitor's segment intersection).
std::pair<double, double> firstLegCrossing(const hameritt::geometry::Polygon& poly) {
  const Leg& l = kLegs[0];
  auto inside = [&](double t) {
    const Vector3d p = l.a + (l.b - l.a) * ((t - l.t0) / (l.t1 - l.t0));
    return poly.contains(p.head<2>());
  };
  auto bisect = [&](double lo, double hi) {  // inside(lo) != inside(hi)
    const bool at_lo = inside(lo);
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (lo + hi);
      (inside(mid) == at_lo ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  };
  double first = -1, last = -1;
  for (double t = l.t0; t <= l.t1; t += 0.5) {
    if (inside(t) && first < 0) first = t;
    if (inside(t)) last = t;
  }
  EXPECT_GE(first, 0.0);
  return {bisect(first - 0.5, first), bisect(last, last + 0.5)};
}

std::string param(const std::string& name) {
  std::string v;
  EXPECT_TRUE(ros::param::get(name, v)) << name;
  return v;
}

}  // namespace

TEST(AdkConstraints, ActiveZoneReportedExactlyInactiveNotAndCheckPathAgrees) {
  ros::NodeHandle nh;
  hameritt::testing::FakeSimulator sim(nh);
  hameritt::testing::Collector<hameritt::ConstraintStatus> status(nh, "/adk/constraints");
  hameritt::testing::Collector<hameritt::ConstraintEvent> events(nh, "/adk/constraint_events");
  hameritt::testing::Collector<hameritt::MissionState> state(nh, "/adk/state");
  ASSERT_TRUE(sim.waitForSubscribers(30)) << "adk node not subscribed";
  ASSERT_TRUE(hameritt::testing::spinUntil(
      [&] { return status.connected() && events.connected() && state.connected(); }, 30));

  std::vector<hameritt::adk::PathSample> samples;
  const int n = static_cast<int>(kLegs.back().t1 * 20);
  for (int k = 0; k <= n; ++k) {
    const double t = hameritt::testing::FakeSimulator::quantized(0.05 * k);
    Vector3d v;
    const Vector3d p = positionAt(t, &v);
    sim.publish(t, p, v);
    samples.push_back({t, p});
    // About 10x real time, and callbacks of our own collectors served meanwhile.
    ros::spinOnce();
    ros::WallDuration(0.004).sleep();
  }
  const double t_end = samples.back().t;
  ASSERT_TRUE(hameritt::testing::spinUntil(
      [&] { return !status.all.empty() && status.last().header.stamp.toSec() >= t_end - 0.1; }, 30))
      << "constraint status did not reach the end of the flight";
  ASSERT_TRUE(hameritt::testing::spinUntil(
      [&] { return !state.all.empty() && state.last().state == "running"; }, 10));

  const auto mission = hameritt::scenario::loadMission(param("/adk/mission"));
  const auto& zone1 = mission.kozs[0];
  ASSERT_EQ(zone1.id, "koz_1");
  ASSERT_EQ(*zone1.window.net, 20.0);
  ASSERT_EQ(*zone1.window.nlt, 60.0);
  const auto [t_in, t_out] = firstLegCrossing(zone1.polygon);
  ASSERT_GT(t_in, 20.0);
  ASSERT_LT(t_in, 60.0);
  ASSERT_GT(t_out, 60.0);

  // The node: one violation of koz_1, from the exact entry to the window's end; none of koz_2.
  const hameritt::ConstraintStatus& s = status.last();
  ASSERT_EQ(s.violations.size(), 1u);
  EXPECT_EQ(s.violation_count, 1u);
  EXPECT_EQ(s.violations[0].zone_id, "koz_1");
  EXPECT_EQ(s.violations[0].purpose, "vantage_denial");
  EXPECT_NEAR(s.violations[0].t_enter, t_in, 1e-6);
  EXPECT_NEAR(s.violations[0].t_exit, 60.0, 1e-9);
  EXPECT_FALSE(s.violations[0].ongoing);
  EXPECT_TRUE(s.active_violations.empty());
  EXPECT_NEAR(s.violation_duration, 60.0 - t_in, 1e-6);
  for (const auto& z : s.keep_out_zones) {
    EXPECT_FALSE(z.violating) << z.id;
    EXPECT_FALSE(z.inside) << z.id;  // hovering north of koz_2
  }

  // Events: koz_1 entered active, violation start/end, exit while inactive; koz_2 entered and
  // left while inactive, with no violation.
  std::vector<std::string> koz1, koz2;
  for (const auto& e : events.all) {
    if (e.id == "koz_1") koz1.push_back(e.event + (e.active ? "+" : "-"));
    if (e.id == "koz_2") koz2.push_back(e.event + (e.active ? "+" : "-"));
    if (e.id == "koz_1" && e.event == "enter") {
      EXPECT_NEAR(e.header.stamp.toSec(), t_in, 1e-6);
    }
    if (e.id == "koz_1" && e.event == "exit") {
      EXPECT_NEAR(e.header.stamp.toSec(), t_out, 1e-6);
    }
    if (e.id == "koz_1" && e.event == "violation_end") {
      EXPECT_NEAR(e.header.stamp.toSec(), 60.0, 1e-6);
    }
  }
  EXPECT_EQ(koz1,
            (std::vector<std::string>{"enter+", "violation_start+", "violation_end+", "exit-"}));
  // koz_2 twice: the descent cuts its corner below 36 m, then the northbound leg crosses it.
  EXPECT_EQ(koz2, (std::vector<std::string>{"enter-", "exit-", "enter-", "exit-"}));

  // hameritt_check_path on the same samples, up to the one the last status was made from.
  const std::string dir = "/tmp/hameritt_adk_constraints_" + std::to_string(::getpid());
  ASSERT_EQ(std::system(("mkdir -p " + dir).c_str()), 0);
  {
    std::vector<hameritt::adk::PathSample> upto;
    for (const auto& p : samples) {
      if (p.t <= s.header.stamp.toSec()) upto.push_back(p);
    }
    ASSERT_NEAR(upto.back().t, s.header.stamp.toSec(), 1e-6);
    std::ofstream f(dir + "/path.csv");
    f << hameritt::adk::pathCsv(upto);
  }
  const std::string cmd = std::string(HAMERITT_BIN_DIR) + "/hameritt_check_path --mission " +
                          param("/adk/mission") + " --path " + dir + "/path.csv --out " + dir +
                          "/report.json > /dev/null";
  const int rc = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(rc));
  EXPECT_EQ(WEXITSTATUS(rc), 3) << cmd;
  std::ifstream rf(dir + "/report.json");
  const auto report = nlohmann::json::parse(rf);
  ASSERT_EQ(report["violation_count"], 1);
  const auto& rv = report["violations"][0];
  EXPECT_EQ(rv["zone"], s.violations[0].zone_id);
  EXPECT_NEAR(rv["t_enter"].get<double>(), s.violations[0].t_enter, 1e-9);
  EXPECT_NEAR(rv["t_exit"].get<double>(), s.violations[0].t_exit, 1e-9);
  EXPECT_NEAR(report["violation_duration"].get<double>(), s.violation_duration, 1e-9);
  ASSERT_EQ(report["aoi_time"].size(), s.areas_of_interest.size());
  for (std::size_t i = 0; i < s.areas_of_interest.size(); ++i) {
    EXPECT_EQ(report["aoi_time"][i]["id"], s.areas_of_interest[i].id);
    EXPECT_NEAR(report["aoi_time"][i]["time_inside"].get<double>(),
                s.areas_of_interest[i].time_inside, 1e-9);
    EXPECT_EQ(report["aoi_time"][i]["entries"].get<unsigned>(), s.areas_of_interest[i].entries);
  }
  std::system(("rm -rf " + dir).c_str());
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "adk_constraints_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
