// rostest: the mission lifecycle of three adk nodes fed the same flight. /timeout reaches its
// 4 s time limit, writes metrics.json (outcome timeout, plausible figures) and exits by itself
// (shutdown_on_end); /crash gets a crash event (outcome crashed); /abort gets SIGINT before the
// end (outcome aborted, metrics still written).
#include <gtest/gtest.h>
#include <ros/master.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <signal.h>
#include <xmlrpcpp/XmlRpcClient.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "adk_test_client.h"
#include "hameritt/CrashEvent.h"
#include "hameritt/MissionMetrics.h"
#include "hameritt/MissionState.h"
#include "hameritt/adk/metrics.h"

using Eigen::Vector3d;
using hameritt::testing::Collector;
using hameritt::testing::spinUntil;

namespace {

const std::string kRoot = "/tmp/hameritt_adk_lifecycle";

// The node's URI from the master, or "" when it is not registered.
std::string nodeUri(const std::string& node) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  args[1] = node;
  if (!ros::master::execute("lookupNode", args, result, payload, false)) return "";
  if (!result.valid() || static_cast<int>(result[0]) != 1) return "";
  return static_cast<std::string>(payload);
}

// The process id of a node, through its slave API (getPid).
int nodePid(const std::string& node) {
  std::string host;
  std::uint32_t port = 0;
  if (!ros::network::splitURI(nodeUri(node), host, port)) return -1;
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue args, result;
  args[0] = ros::this_node::getName();
  if (!client.execute("getPid", args, result) || static_cast<int>(result[0]) != 1) return -1;
  return static_cast<int>(result[2]);
}

// Take-off to 10 m at 5 m/s, then east at 5 m/s.
Vector3d flight(double t, Vector3d* v) {
  if (t < 2.0) {
    *v = Vector3d(0, 0, 5);
    return Vector3d(-279, -258, 5 * t);
  }
  *v = Vector3d(5, 0, 0);
  return Vector3d(-279 + 5 * (t - 2.0), -258, 10);
}

nlohmann::json readMetrics(const std::string& ns) {
  return hameritt::testing::readJsonFile(kRoot + "/" + ns + "/metrics.json");
}

}  // namespace

TEST(AdkLifecycle, TimeoutCrashAndAbort) {
  ros::NodeHandle nh;
  std::filesystem::remove_all(kRoot);
  hameritt::testing::FakeSimulator sim(nh, {"/timeout", "/crash", "/abort"});
  ros::Publisher crash_pub = nh.advertise<hameritt::CrashEvent>("/crash/uav/crash", 1, true);
  Collector<hameritt::MissionState> timeout_state(nh, "/timeout/adk/state");
  Collector<hameritt::MissionMetrics> timeout_metrics(nh, "/timeout/adk/metrics");
  Collector<hameritt::MissionState> crash_state(nh, "/crash/adk/state");
  ASSERT_TRUE(sim.waitForSubscribers(30, 3)) << "adk nodes not subscribed";
  ASSERT_TRUE(spinUntil(
      [&] {
        return crash_pub.getNumSubscribers() > 0 && timeout_state.connected() &&
               timeout_metrics.connected() && crash_state.connected();
      },
      30));
  const int abort_pid = nodePid("/abort/adk");
  ASSERT_GT(abort_pid, 0);

  for (int k = 0; k <= 225; ++k) {  // 50 Hz to 4.5 s
    const double t = hameritt::testing::FakeSimulator::quantized(0.02 * k);
    Vector3d v;
    sim.publish(t, flight(t, &v), v);
    if (k == 125) {  // 2.5 s
      hameritt::CrashEvent c;
      c.header.stamp.fromSec(t);
      c.header.frame_id = "map";
      c.entity_id = "house_12";
      c.speed = 5.0;
      crash_pub.publish(c);
    }
    if (k == 150) {                          // 3.0 s
      spinUntil([] { return false; }, 0.2);  // let the abort node take 3.0 s
      ASSERT_EQ(::kill(abort_pid, SIGINT), 0);
    }
    ros::spinOnce();
    ros::WallDuration(0.004).sleep();
  }

  // Timeout.
  ASSERT_TRUE(timeout_metrics.waitFor(1, 20)) << "no /timeout/adk/metrics";
  EXPECT_EQ(timeout_metrics.last().outcome, "timeout");
  EXPECT_EQ(timeout_metrics.last().metrics_file, kRoot + "/timeout/metrics.json");
  ASSERT_TRUE(spinUntil([&] { return timeout_state.last().state == "timeout"; }, 5));
  const auto tm = readMetrics("timeout");
  ASSERT_FALSE(tm.empty());
  EXPECT_EQ(tm["schema"], "hameritt/metrics");
  EXPECT_EQ(tm["outcome"], "timeout");
  EXPECT_NE(tm["reason"].get<std::string>().find("time limit 4 s reached"), std::string::npos);
  EXPECT_EQ(tm["mode"], "maneuver_only");
  EXPECT_EQ(tm["time_limit"], 4.0);
  const double end = tm["end_time"];
  EXPECT_GE(end, 4.0);
  EXPECT_LE(end, 4.0 + 1e-6);  // odometry at 4.0 s ends it
  EXPECT_NEAR(tm["start_time"].get<double>(), 0.02, 1e-6);
  const auto& f = tm["flight"];
  // 10 m up, 10 m east; airborne from the first sample (it moves).
  EXPECT_NEAR(f["path_length"].get<double>(), 20.0, 1e-6);
  EXPECT_NEAR(f["flight_time"].get<double>(), 4.0, 1e-6);
  EXPECT_NEAR(f["max_speed"].get<double>(), 5.0, 1e-9);
  const double hover = hameritt::adk::EnergyModel().hoverPower();
  EXPECT_EQ(f["energy_model"]["hover_power"].get<double>(), hover);
  EXPECT_GT(f["energy"].get<double>(), 0.95 * hover * f["flight_time"].get<double>());
  EXPECT_LT(f["energy"].get<double>(), 1.5 * hover * f["flight_time"].get<double>());
  EXPECT_EQ(tm["keep_out_zones"]["violation_count"], 0);
  EXPECT_EQ(tm["detections"]["total"], 0);
  EXPECT_FALSE(tm["targets"][0]["found"].get<bool>());
  EXPECT_TRUE(tm["time_to_first_correct_detection"].is_null());
  EXPECT_EQ(tm["coverage"]["areas_of_interest"].size(), 2u);
  EXPECT_EQ(tm["scenario_id"], timeout_metrics.last().scenario_id);
  // shutdown_on_end: the node leaves by itself shortly after.
  EXPECT_TRUE(spinUntil([] { return nodeUri("/timeout/adk").empty(); }, 15))
      << "/timeout/adk still running";

  // Crash.
  ASSERT_TRUE(spinUntil(
      [&] { return !crash_state.all.empty() && crash_state.last().state == "crashed"; }, 10));
  const auto cm = readMetrics("crash");
  EXPECT_EQ(cm["outcome"], "crashed");
  EXPECT_NE(cm["reason"].get<std::string>().find("house_12"), std::string::npos);
  EXPECT_NEAR(cm["end_time"].get<double>(), 2.5, 1e-9);
  EXPECT_NEAR(cm["flight"]["path_length"].get<double>(), 12.5, 0.15);  // odometry to ~2.5 s
  EXPECT_FALSE(nodeUri("/crash/adk").empty());  // shutdown_on_end false: still up

  // Abort.
  EXPECT_TRUE(spinUntil([] { return nodeUri("/abort/adk").empty(); }, 15))
      << "/abort/adk did not exit on SIGINT";
  ASSERT_TRUE(spinUntil([] { return std::filesystem::exists(kRoot + "/abort/metrics.json"); }, 10));
  const auto am = readMetrics("abort");
  EXPECT_EQ(am["outcome"], "aborted");
  EXPECT_NE(am["reason"].get<std::string>().find("interrupted"), std::string::npos);
  EXPECT_GE(am["end_time"].get<double>(), 3.0 - 1e-9);
  EXPECT_LT(am["end_time"].get<double>(), 4.0);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "adk_lifecycle_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
