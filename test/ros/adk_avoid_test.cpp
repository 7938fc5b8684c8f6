// rostest: the ADK scores avoid missions. Two adk nodes on the same avoid scenario
// (test/data/avoid_*.json) get different flights: /clean climbs to 45 m, between the aircraft's
// altitudes, flies to above the goal and lands on it; /close rides 2 m above aircraft_1 for
// 2 s, then flies straight to the goal. The test's own judge (linear interpolation of the
// aircraft's keyframes read from sim_config.json, the separation cylinder, path lengths and SPL
// from the samples it sent) decides what each flight did; the ADK's metrics.json must agree:
// /clean succeeds with SPL = shortest / flown, /close fails at the reach with the separation
// lost. The judge's finding a loss on /close and none on /clean is its own negative control.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "adk_test_client.h"
#include "hameritt/AvoidStatus.h"
#include "hameritt/BoundingBoxArray.h"
#include "hameritt/MissionMetrics.h"
#include "hameritt/MissionState.h"
#include "hameritt/PerceptionReport.h"

using Eigen::Vector3d;
using hameritt::testing::Collector;
using hameritt::testing::spinUntil;

namespace {

const std::string kRoot = "/tmp/hameritt_adk_avoid";
// The last /clock the flights published: later tests keep time going forward.
double g_clock_end = 0.0;

struct Keyframes {
  std::string id;
  std::vector<std::array<double, 4>> k;  // t, x, y, z
  Vector3d at(double t) const {
    if (t <= k.front()[0]) return {k.front()[1], k.front()[2], k.front()[3]};
    if (t >= k.back()[0]) return {k.back()[1], k.back()[2], k.back()[3]};
    std::size_t i = 1;
    while (k[i][0] < t) ++i;
    const double u = (t - k[i - 1][0]) / (k[i][0] - k[i - 1][0]);
    return {k[i - 1][1] + u * (k[i][1] - k[i - 1][1]), k[i - 1][2] + u * (k[i][2] - k[i - 1][2]),
            k[i - 1][3] + u * (k[i][3] - k[i - 1][3])};
  }
};

// What the test's judge finds in a flight: up to and including the first sample within the
// goal radius.
struct Judged {
  bool reached = false;
  double reach_time = 0.0, path = 0.0, min_distance = 1e18;
  int loss_samples = 0;
};

struct Sample {
  double t;
  Vector3d p, v;
};

Judged judge(const std::vector<Sample>& flight, const std::vector<Keyframes>& aircraft,
             const Vector3d& goal, double radius, double min_h, double min_v) {
  Judged j;
  for (std::size_t i = 0; i < flight.size(); ++i) {
    const Sample& s = flight[i];
    if (i > 0) j.path += (s.p - flight[i - 1].p).norm();
    for (const auto& a : aircraft) {
      const Vector3d d = s.p - a.at(s.t);
      j.min_distance = std::min(j.min_distance, d.norm());
      if (d.head<2>().norm() < min_h && std::abs(d.z()) < min_v) ++j.loss_samples;
    }
    if ((s.p - goal).norm() <= radius) {
      j.reached = true;
      j.reach_time = s.t;
      break;
    }
  }
  return j;
}

// Straight segments through `points` at `speed`, sampled every `dt` from t0.
void fly(std::vector<Sample>* out, const std::vector<Vector3d>& points, double speed, double dt) {
  double t = out->empty() ? 0.0 : out->back().t;
  for (std::size_t i = 1; i < points.size(); ++i) {
    const Vector3d d = points[i] - points[i - 1];
    const int n = std::max(1, static_cast<int>(std::ceil(d.norm() / (speed * dt))));
    const Vector3d v = d / (n * dt);
    for (int k = 1; k <= n; ++k) {
      t = hameritt::testing::FakeSimulator::quantized(t + dt);
      out->push_back({t, points[i - 1] + d * (static_cast<double>(k) / n), v});
    }
  }
}

}  // namespace

TEST(AdkAvoid, CleanFlightSucceedsCloseFlightFails) {
  ros::NodeHandle nh;
  std::filesystem::remove_all(kRoot);
  std::string data;
  ASSERT_TRUE(ros::NodeHandle("~").getParam("data_dir", data)) << "~data_dir not set";
  data += "/";
  const auto mission = hameritt::testing::readJsonFile(data + "avoid_mission.json");
  const auto sim = hameritt::testing::readJsonFile(data + "avoid_sim_config.json");
  ASSERT_EQ(mission["phases"].size(), 1u);
  const auto& phase = mission["phases"][0];
  ASSERT_EQ(phase["type"], "avoid");
  const Vector3d goal(phase["goal"][0], phase["goal"][1], phase["goal"][2]);
  const double radius = phase["goal_radius"], shortest = phase["shortest_path_m"];
  const double min_h = phase["criteria"]["min_horizontal_separation"];
  const double min_v = phase["criteria"]["min_vertical_separation"];
  std::vector<Keyframes> aircraft;
  for (const auto& a : sim["aircraft"]) {
    Keyframes k;
    k.id = a["id"];
    for (const auto& p : a["trajectory"]) k.k.push_back({p[0], p[1], p[2], p[3]});
    aircraft.push_back(k);
  }
  ASSERT_GE(aircraft.size(), 2u);
  const Vector3d start(sim["uav"]["start"]["x"], sim["uav"]["start"]["y"],
                       sim["uav"]["start"]["z"]);

  // The two flights, 20 Hz.
  const double dt = 0.05;
  std::vector<Sample> clean{{0.0, start, Vector3d::Zero()}};
  fly(&clean,
      {start, start + Vector3d(0, 0, 45), Vector3d(goal.x(), goal.y(), 45),
       goal + Vector3d(0, 0, 1)},
      12.0, dt);
  std::vector<Sample> close;
  for (double t = 0.0; t <= 2.0 + 1e-9; t += dt) {
    const double q = hameritt::testing::FakeSimulator::quantized(t);
    close.push_back({q, aircraft[0].at(q) + Vector3d(0, 0, 2), Vector3d::Zero()});
  }
  fly(&close, {close.back().p, goal + Vector3d(0, 0, 1)}, 25.0, dt);

  const Judged jc = judge(clean, aircraft, goal, radius, min_h, min_v);
  const Judged jx = judge(close, aircraft, goal, radius, min_h, min_v);
  ASSERT_TRUE(jc.reached);
  ASSERT_TRUE(jx.reached);
  ASSERT_EQ(jc.loss_samples, 0) << "the clean flight is not clean: pick another altitude";
  ASSERT_GT(jx.loss_samples, 30) << "the judge must see the close flight's loss";

  hameritt::testing::FakeSimulator fake(nh, {"/clean", "/close"});
  Collector<hameritt::MissionMetrics> clean_metrics(nh, "/clean/adk/metrics");
  Collector<hameritt::MissionMetrics> close_metrics(nh, "/close/adk/metrics");
  Collector<hameritt::MissionState> close_state(nh, "/close/adk/state");
  Collector<hameritt::AvoidStatus> clean_live(nh, "/clean/adk/avoid");
  Collector<hameritt::AvoidStatus> close_live(nh, "/close/adk/avoid");
  ASSERT_TRUE(fake.waitForSubscribers(30, 2)) << "adk nodes not subscribed";
  ASSERT_TRUE(spinUntil(
      [&] {
        return clean_metrics.connected() && close_metrics.connected() && close_state.connected() &&
               clean_live.connected() && close_live.connected();
      },
      30));
  const std::size_t n = std::max(clean.size(), close.size());
  for (std::size_t i = 0; i < n; ++i) {
    const double t = hameritt::testing::FakeSimulator::quantized(dt * static_cast<double>(i));
    const Sample& a = clean[std::min(i, clean.size() - 1)];
    const Sample& b = close[std::min(i, close.size() - 1)];
    if (i < clean.size()) fake.publishOdometry(0, t, a.p, a.v);
    if (i < close.size()) fake.publishOdometry(1, t, b.p, b.v);
    fake.clock(t);
    g_clock_end = t;
    ros::spinOnce();
    ros::WallDuration(0.002).sleep();
  }
  ASSERT_TRUE(clean_metrics.waitFor(1, 20)) << "no /clean/adk/metrics";
  ASSERT_TRUE(close_metrics.waitFor(1, 20)) << "no /close/adk/metrics";

  const auto cm = hameritt::testing::readJsonFile(kRoot + "/clean/metrics.json");
  ASSERT_TRUE(cm.contains("avoid")) << cm.dump(2);
  const auto& ca = cm["avoid"];
  EXPECT_EQ(cm["outcome"], "success") << cm["reason"];
  EXPECT_NE(cm["reason"].get<std::string>().find("reached the goal"), std::string::npos);
  EXPECT_TRUE(ca["success"].get<bool>());
  EXPECT_EQ(ca["failure"], "");
  EXPECT_NEAR(ca["reach_time"].get<double>(), jc.reach_time, 1e-6);
  EXPECT_NEAR(cm["end_time"].get<double>(), jc.reach_time, 1e-6);
  // The path from the first odometry sample (t = 0) to the reach.
  EXPECT_NEAR(ca["path_length"].get<double>(), jc.path, 1e-6);
  EXPECT_NEAR(ca["spl"].get<double>(), shortest / std::max(shortest, jc.path), 1e-9);
  EXPECT_EQ(ca["separation_losses"], 0);
  EXPECT_EQ(ca["seconds_below_minimum"], 0.0);
  EXPECT_FALSE(ca["contact"].get<bool>());
  EXPECT_NEAR(ca["min_separation"].get<double>(), jc.min_distance, 0.05);
  EXPECT_EQ(ca["shortest_path"].get<double>(), shortest);

  const auto xm = hameritt::testing::readJsonFile(kRoot + "/close/metrics.json");
  ASSERT_TRUE(xm.contains("avoid")) << xm.dump(2);
  const auto& xa = xm["avoid"];
  EXPECT_EQ(xm["outcome"], "failed") << xm["reason"];
  EXPECT_NE(xm["reason"].get<std::string>().find("lost separation"), std::string::npos)
      << xm["reason"];
  ASSERT_TRUE(spinUntil([&] { return close_state.last().state == "failed"; }, 5));
  EXPECT_FALSE(xa["success"].get<bool>());
  EXPECT_NEAR(xa["reach_time"].get<double>(), jx.reach_time, 1e-6);
  EXPECT_GE(xa["separation_losses"].get<int>(), 1);
  // The loss lasts from the first sample to where the straight leg leaves the cylinder.
  EXPECT_GE(xa["seconds_below_minimum"].get<double>(), 2.0);
  EXPECT_NEAR(xa["min_separation"].get<double>(), 2.0, 0.01);
  EXPECT_EQ(xa["closest_aircraft"], aircraft[0].id);
  EXPECT_FALSE(xa["contact"].get<bool>());
  EXPECT_EQ(xa["spl"].get<double>(), 0.0);

  // The live score (adk/avoid, status rate): the close flight's shows the loss while it rides
  // above the aircraft; the last message of each (at the end) says what metrics.json says.
  ASSERT_TRUE(spinUntil([&] { return clean_live.last().reached && close_live.last().reached; }, 5));
  bool lost_live = false;
  for (const auto& m : close_live.all) {
    if (m.header.stamp.toSec() <= 2.0 && m.separation_lost) lost_live = true;
  }
  EXPECT_TRUE(lost_live) << close_live.all.size() << " messages";
  EXPECT_GT(close_live.all.size(), 10u);
  for (const auto& m : clean_live.all) EXPECT_FALSE(m.separation_lost) << m.header.stamp.toSec();
  EXPECT_EQ(close_live.last().separation_losses, xa["separation_losses"].get<unsigned>());
  EXPECT_EQ(close_live.last().min_separation, xa["min_separation"].get<double>());
  EXPECT_EQ(close_live.last().reach_time, xa["reach_time"].get<double>());
  EXPECT_EQ(clean_live.last().path_length, ca["path_length"].get<double>());
  EXPECT_EQ(clean_live.last().phase, "avoid_1");

  // Both files pass the published schema as python3-jsonschema reads it; a copy with an SPL
  // above 1 does not (the control).
  {
    nlohmann::json bad = xm;
    bad["avoid"]["spl"] = 1.5;
    std::ofstream(kRoot + "/bad_metrics.json") << bad.dump();
  }
  const std::string check =
      "/usr/bin/python3 -c 'import json, sys, jsonschema\n"
      "s = json.load(open(sys.argv[1]))\n"
      "jsonschema.validate(json.load(open(sys.argv[2])), s)' " +
      data + "../../config/schema/metrics.schema.json ";
  EXPECT_EQ(std::system((check + kRoot + "/clean/metrics.json").c_str()), 0);
  EXPECT_EQ(std::system((check + kRoot + "/close/metrics.json").c_str()), 0);
  EXPECT_NE(std::system((check + kRoot + "/bad_metrics.json 2>/dev/null").c_str()), 0);
}

// Perfect perception on an avoid mission: a camera's box of another aircraft becomes a
// perceived entity of class aircraft at the aircraft's scripted pose (its body centre) at the
// image's stamp, with its model; a box whose id is no entity and no aircraft is left out.
TEST(AdkAvoid, PerfectPerceptionReportsASeenAircraft) {
  ros::NodeHandle nh;
  std::string data;
  ASSERT_TRUE(ros::NodeHandle("~").getParam("data_dir", data)) << "~data_dir not set";
  const auto sim = hameritt::testing::readJsonFile(data + "/avoid_sim_config.json");
  const auto& a0 = sim["aircraft"][0];
  Keyframes k;
  for (const auto& p : a0["trajectory"]) k.k.push_back({p[0], p[1], p[2], p[3]});
  ros::Publisher boxes_pub =
      nh.advertise<hameritt::BoundingBoxArray>("/seen/uav/camera/down/boxes", 10);
  ros::Publisher clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10, true);
  Collector<hameritt::PerceptionReport> reports(nh, "/seen/adk/perfect_perception");
  ASSERT_TRUE(
      spinUntil([&] { return boxes_pub.getNumSubscribers() > 0 && reports.connected(); }, 30))
      << "/seen adk node not connected";
  const double t = g_clock_end + 1.0;
  rosgraph_msgs::Clock c;
  c.clock.fromSec(t);
  clock_pub.publish(c);
  spinUntil([] { return false; }, 0.3);
  auto box = [](const std::string& id) {
    hameritt::BoundingBox b;
    b.entity_id = id;
    b.entity_class = "aircraft";
    b.role = "aircraft";
    b.x_min = 10;
    b.y_min = 20;
    b.x_max = 60;
    b.y_max = 45;
    b.visible_pixels = 900;
    b.total_pixels = 1000;
    b.occlusion = 0.1f;
    return b;
  };
  hameritt::BoundingBoxArray frame;
  frame.header.stamp.fromSec(t);
  frame.header.frame_id = "uav/camera_down_optical";
  frame.camera = "down";
  frame.boxes = {box(a0["id"]), box("aircraft_99")};
  boxes_pub.publish(frame);
  ASSERT_TRUE(reports.waitFor(1, 10)) << "no perfect perception report";
  const auto& r = reports.all[0];
  ASSERT_EQ(r.entities.size(), 1u) << "only the known aircraft";
  const auto& e = r.entities[0];
  EXPECT_EQ(e.entity_id, a0["id"].get<std::string>());
  EXPECT_EQ(e.entity_class, "aircraft");
  EXPECT_EQ(e.role, "aircraft");
  ASSERT_EQ(e.attributes.size(), 1u);
  EXPECT_EQ(e.attributes[0].key, "model");
  EXPECT_EQ(e.attributes[0].value, a0["model"].get<std::string>());
  const Vector3d p = k.at(t);
  EXPECT_NEAR(e.position.x, p.x(), 1e-3);
  EXPECT_NEAR(e.position.y, p.y(), 1e-3);
  EXPECT_NEAR(e.position.z, p.z(), 1e-3);
  EXPECT_EQ(e.box.visible_pixels, 900u);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "adk_avoid_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
