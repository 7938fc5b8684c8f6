// rostest: hostile messages (NaN/Inf/absurd setpoints and waypoints, empty and huge paths,
// unknown frames and entity ids, out-of-order stamps, a mission of another scenario) sent to the
// simulator, planner, ADK and both baseline clients. Every node keeps running and logs one clear
// error per kind of input; the UAV stays finite and inside the simulator's geofence; valid
// commands afterwards still work.
#include <gtest/gtest.h>
#include <nav_msgs/Path.h>
#include <ros/master.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <xmlrpcpp/XmlRpcClient.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "adk_test_client.h"
#include "hameritt/BoundingBoxArray.h"
#include "hameritt/Detection.h"
#include "hameritt/DetectionScore.h"
#include "hameritt/EntityStateArray.h"
#include "hameritt/FollowProgress.h"
#include "hameritt/Mission.h"
#include "hameritt/MissionState.h"
#include "hameritt/PlanPath.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/sim_config_io.h"
#include "sim_test_client.h"

namespace {

using hameritt::testing::Collector;
using hameritt::testing::spinUntil;

const double kNan = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

// Every message of every node on /rosout.
struct Rosout {
  explicit Rosout(ros::NodeHandle& nh) : log(nh, "/rosout", 100000) {}
  // ERROR lines of `node` containing every one of `parts`, once there is one (or after 10 wall
  // seconds without): the condition, not a fixed sleep, ends the wait.
  int errors(const std::string& node, const std::vector<std::string>& parts) {
    spinUntil([&] { return count(node, parts) > 0; }, 10);
    return count(node, parts);
  }
  // The same, now.
  int count(const std::string& node, const std::vector<std::string>& parts) {
    ros::spinOnce();
    int n = 0;
    for (const auto& m : log.all) {
      if (m.name != node || m.level != rosgraph_msgs::Log::ERROR) continue;
      bool all = true;
      for (const auto& p : parts) all = all && m.msg.find(p) != std::string::npos;
      n += all;
    }
    return n;
  }
  std::string dump(const std::string& node) const {
    std::string out;
    for (const auto& m : log.all) {
      if (m.name == node && m.level >= rosgraph_msgs::Log::WARN) out += m.msg + "\n";
    }
    return out;
  }
  Collector<rosgraph_msgs::Log> log;
};

// The node answers on its XML-RPC slave API (what `rosnode ping` does).
bool alive(const std::string& node) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  args[1] = node;
  if (!ros::master::execute("lookupNode", args, result, payload, false)) return false;
  std::string host;
  uint32_t port = 0;
  if (!ros::network::splitURI(static_cast<std::string>(payload), host, port)) return false;
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue a, r;
  a[0] = ros::this_node::getName();
  return client.execute("getPid", a, r) && r.valid() && static_cast<int>(r[0]) == 1;
}

struct Fence {
  hameritt::geometry::Vec3 min, max;
};

Fence fenceOf(const std::string& sim_config) {
  const auto config = hameritt::scenario::loadSimConfig(sim_config);
  const auto world = hameritt::scenario::generateCheckedWorld(config, sim_config);
  const auto b = world.bounds();
  return {{b.min.x() - 50, b.min.y() - 50, 0.0},
          {b.max.x() + 50, b.max.y() + 50, config.uav.altitude_max + 50}};
}

// Shared by the tests (one graph, in declaration order).
struct Graph {
  Graph()
      : rosout(nh),
        flight(nh, "/uav/odom", 200000),
        progress(nh, "/planner/progress", 1000),
        scores(nh, "/adk/detection_scores", 100),
        states(nh, "/adk/state", 1000),
        missions(nh, "/mission", 10) {
    std::string path;
    ros::param::get("/hostile_sim_config", path);
    fence = fenceOf(path);
    cmd_vel = nh.advertise<geometry_msgs::Twist>("/uav/cmd_vel", 100);
    cmd_pose = nh.advertise<geometry_msgs::PoseStamped>("/uav/cmd_pose", 100);
    waypoints = nh.advertise<nav_msgs::Path>("/planner/waypoints", 100);
    odom = nh.advertise<nav_msgs::Odometry>("/uav/odom", 100);
    detections = nh.advertise<hameritt::Detection>("/perception/detections", 100);
    truth = nh.advertise<hameritt::EntityStateArray>("/ground_truth/entities", 100);
    boxes = nh.advertise<hameritt::BoundingBoxArray>("/uav/camera/down/boxes", 100);
    mission = nh.advertise<hameritt::Mission>("/mission", 10);
  }
  // Every odometry sample finite and inside the fence.
  std::string badSample() {
    ros::spinOnce();
    for (const auto& o : flight.all) {
      if (o.child_frame_id == "hostile") continue;  // the test's own
      const auto& p = o.pose.pose.position;
      const hameritt::geometry::Vec3 v(p.x, p.y, p.z);
      if (!v.allFinite()) return "non-finite odometry at " + std::to_string(o.header.stamp.toSec());
      if ((v.array() < fence.min.array()).any() || (v.array() > fence.max.array()).any()) {
        return "outside the fence at t = " + std::to_string(o.header.stamp.toSec()) + ": (" +
               std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
      }
    }
    return "";
  }
  // Publishes and gives the nodes time to take it.
  template <class M>
  void send(ros::Publisher& pub, const M& m) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(10);
    while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < until) {
      ros::WallDuration(0.01).sleep();
    }
    pub.publish(m);
  }

  ros::NodeHandle nh;
  Rosout rosout;
  Collector<nav_msgs::Odometry> flight;
  Collector<hameritt::FollowProgress> progress;
  Collector<hameritt::DetectionScore> scores;
  Collector<hameritt::MissionState> states;
  Collector<hameritt::Mission> missions;
  Fence fence;
  ros::Publisher cmd_vel, cmd_pose, waypoints, odom, detections, truth, boxes, mission;
};

Graph* g = nullptr;
hameritt::testing::SimClient* sim = nullptr;
int cases = 0;  // hostile messages and requests sent

// Odometry samples the test must have seen at least (asserted at the end). The simulator
// publishes one every physics_rate_hz / publish_rate_hz steps and queues at most kOdomQueue per
// subscriber (src/ros/simulator_ros.cpp): a call of 5000 steps publishes 2500 at once and the
// oldest are dropped when the queue is full, but the newest kOdomQueue of each call are always
// delivered (SimClient::step waits for the call's last one).
constexpr unsigned kOdomQueue = 50;
double guaranteed_samples = 0;

// Advances `steps` physics steps and counts the samples that must arrive.
void fly(unsigned steps) {
  static const double steps_per_sample = [] {
    double physics_hz = 0, publish_hz = 0;
    EXPECT_TRUE(ros::param::get("/simulator/physics_rate_hz", physics_hz));
    EXPECT_TRUE(ros::param::get("/simulator/publish_rate_hz", publish_hz));
    return physics_hz / publish_hz;
  }();
  sim->step(steps);
  guaranteed_samples += std::min<double>(kOdomQueue, std::floor(steps / steps_per_sample));
}

geometry_msgs::Twist twist(double x, double y, double z, double w) {
  geometry_msgs::Twist t;
  t.linear.x = x;
  t.linear.y = y;
  t.linear.z = z;
  t.angular.z = w;
  return t;
}

geometry_msgs::PoseStamped pose(double x, double y, double z, const std::string& frame = "map") {
  geometry_msgs::PoseStamped p;
  p.header.frame_id = frame;
  p.pose.position.x = x;
  p.pose.position.y = y;
  p.pose.position.z = z;
  p.pose.orientation.w = 1.0;
  return p;
}

nav_msgs::Path pathOf(const std::vector<hameritt::geometry::Vec3>& pts,
                      const std::string& frame = "map") {
  nav_msgs::Path p;
  p.header.frame_id = frame;
  for (const auto& w : pts) p.poses.push_back(pose(w.x(), w.y(), w.z()));
  return p;
}

TEST(HostileInputs, SimulatorSetpoints) {
  sim->connect();
  sim->setPose(sim->odom.pose.pose.position.x, sim->odom.pose.pose.position.y, 30, 0);
  fly(7500);  // 15 s: take off
  const auto start = sim->odom.pose.pose.position;
  ASSERT_GT(start.z, 20.0);

  // Non-finite velocities: every field, NaN and both infinities.
  for (int field = 0; field < 4; ++field) {
    for (double bad : {kNan, kInf, -kInf}) {
      double v[4] = {1, 1, 0, 0};
      v[field] = bad;
      g->send(g->cmd_vel, twist(v[0], v[1], v[2], v[3]));
      ++cases;
    }
  }
  // Non-finite and foreign-frame poses.
  for (double bad : {kNan, kInf, -kInf}) {
    for (int axis = 0; axis < 3; ++axis) {
      auto p = pose(start.x, start.y, start.z);
      (axis == 0 ? p.pose.position.x : axis == 1 ? p.pose.position.y : p.pose.position.z) = bad;
      g->send(g->cmd_pose, p);
      ++cases;
    }
  }
  g->send(g->cmd_pose, pose(start.x + 500, start.y, start.z, "earth"));
  g->send(g->cmd_pose, pose(start.x + 500, start.y, start.z, "uav/base_link"));
  cases += 2;
  // The simulator took them (its error lines say so) before it steps on.
  EXPECT_EQ(g->rosout.errors("/simulator", {"/uav/cmd_vel", "expected a finite", "ignored"}), 1)
      << g->rosout.dump("/simulator");
  EXPECT_EQ(
      g->rosout.errors("/simulator", {"/uav/cmd_pose", "pose.position.", "expected a finite"}), 1);
  EXPECT_EQ(g->rosout.errors("/simulator", {"/uav/cmd_pose", "header.frame_id", "'map'"}), 1);
  fly(1000);
  // Nothing was taken: the UAV still holds its pose setpoint.
  const auto& held = sim->odom.pose.pose.position;
  EXPECT_NEAR(held.x, start.x, 0.5);
  EXPECT_NEAR(held.y, start.y, 0.5);
  EXPECT_NEAR(held.z, start.z, 0.5);

  // Absurd finite velocity: clamped to the controller's limits; the geofence stops the UAV at
  // the bounds, the ceiling too.
  g->send(g->cmd_vel, twist(1e9, 1e9, 1e9, 1e9));
  ++cases;
  EXPECT_EQ(g->rosout.errors("/simulator", {"/uav/cmd_vel", "clamped", "linear.x/y to 12"}), 1);
  for (int i = 0; i < 30; ++i) fly(5000);  // 150 s at 12 m/s and 3 m/s climb
  EXPECT_EQ(g->badSample(), "");
  const auto& corner = sim->odom.pose.pose.position;
  EXPECT_GT(corner.x, g->fence.max.x() - 60) << "the flight did not reach the fence";
  EXPECT_GT(corner.z, g->fence.max.z() - 40);

  // Absurd pose: clamped onto the fence; a NaN orientation flies with yaw 0.
  auto far = pose(-1e12, -1e12, 1e6);
  far.pose.orientation.w = kNan;
  g->send(g->cmd_pose, far);
  ++cases;
  EXPECT_EQ(g->rosout.errors("/simulator", {"/uav/cmd_pose", "clamped", "to the geofence's"}), 1)
      << g->rosout.dump("/simulator");
  for (int i = 0; i < 6; ++i) fly(5000);
  EXPECT_EQ(g->badSample(), "");

  // Lock-step requests out of range.
  hameritt::StepSimulation too_many;
  too_many.request.steps = 2000000;
  ASSERT_TRUE(ros::service::call("/simulator/step", too_many));
  EXPECT_FALSE(too_many.response.success);
  EXPECT_EQ(too_many.response.code, 2);
  ++cases;

  // A valid command afterwards still works: back to the start.
  sim->setPose(start.x, start.y, 40, 0);
  for (int i = 0; i < 14; ++i) fly(5000);
  const auto& back = sim->odom.pose.pose.position;
  EXPECT_NEAR(back.x, start.x, 2.0);
  EXPECT_NEAR(back.y, start.y, 2.0);
  EXPECT_NEAR(back.z, 40, 2.0);
  EXPECT_EQ(g->badSample(), "");
  EXPECT_TRUE(sim->crashes.empty());
}

TEST(HostileInputs, PlannerRequestsAndWaypoints) {
  ASSERT_TRUE(ros::service::waitForService("/planner/plan_path", ros::Duration(30)));
  const auto here = sim->odom.pose.pose.position;
  auto request = [&](const geometry_msgs::Point& start, const std::vector<geometry_msgs::Point>& w,
                     double t0, bool hostile = true) {
    hameritt::PlanPath srv;
    srv.request.start = start;
    srv.request.waypoints = w;
    srv.request.start_time = t0;
    srv.request.seed = 3;
    EXPECT_TRUE(ros::service::call("/planner/plan_path", srv));
    cases += hostile;
    return srv.response;
  };
  geometry_msgs::Point s = here, goal = here;
  goal.x += 60;
  geometry_msgs::Point nan_start = s;
  nan_start.y = kNan;
  auto r = request(nan_start, {goal}, 0);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.message.find("start.y: expected a finite coordinate"), 0u) << r.message;
  geometry_msgs::Point inf_goal = goal;
  inf_goal.z = kInf;
  r = request(s, {goal, inf_goal}, 0);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.message.find("waypoints[1].z: expected a finite coordinate"), 0u) << r.message;
  r = request(s, {}, 0);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.message.find("at least one waypoint"), std::string::npos) << r.message;
  r = request(s, std::vector<geometry_msgs::Point>(5000, goal), 0);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.message.find("at most 1000 waypoints"), std::string::npos) << r.message;
  r = request(s, {goal}, kNan);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.message.find("start_time"), std::string::npos) << r.message;
  geometry_msgs::Point absurd = goal;
  absurd.x = 1e12;
  r = request(s, {absurd}, 0);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.code, 1) << r.message;  // outside the world: no path, not a crash
  r = request(s, {goal}, 0, false);   // a valid request: not a hostile one
  EXPECT_TRUE(r.success) << r.message;

  // The follower's topic: refused whole, nothing flown.
  using V = hameritt::geometry::Vec3;
  const V h(here.x, here.y, here.z);
  g->send(g->waypoints, pathOf({h + V(40, 0, 0), V(kNan, 0, 30)}));
  g->send(g->waypoints, pathOf({h + V(0, kInf, 0)}));
  g->send(g->waypoints, pathOf(std::vector<V>(20000, h + V(10, 0, 0))));
  g->send(g->waypoints, pathOf({h + V(40, 0, 0)}, "earth"));
  cases += 4;
  const auto refused = [] {
    return g->rosout.count("/planner", {"/planner/waypoints", "poses[", "expected a finite"}) +
           g->rosout.count("/planner", {"/planner/waypoints", "at most 1000"}) +
           g->rosout.count("/planner", {"/planner/waypoints", "header.frame_id"});
  };
  spinUntil([&] { return refused() > 0; }, 10);
  EXPECT_EQ(refused(), 1) << "one throttled line for the hostile lists: "
                          << g->rosout.dump("/planner");
  for (const auto& p : g->progress.all) EXPECT_NE(p.state, "following") << p.message;
  // An empty list stops the follower (documented, so not a hostile message), a valid one is
  // flown.
  g->send(g->waypoints, pathOf({}));
  EXPECT_TRUE(spinUntil(
      [] {
        return !g->progress.all.empty() && g->progress.last().message == "empty waypoint list";
      },
      10));
  g->send(g->waypoints, pathOf({h + V(40, 0, 0)}));
  EXPECT_TRUE(spinUntil(
      [] { return !g->progress.all.empty() && g->progress.last().state == "following"; }, 30))
      << (g->progress.all.empty() ? "" : g->progress.last().message);
  EXPECT_TRUE(alive("/planner"));
}

TEST(HostileInputs, AdkAndClients) {
  const double t = sim->last_time;
  // Odometry: non-finite, then a stamp from the past (the simulator reset or a replayed bag).
  nav_msgs::Odometry o = sim->odom;
  o.child_frame_id = "hostile";
  o.header.stamp.fromSec(t + 0.001);  // newer than the last, else dropped as a duplicate
  o.pose.pose.position.x = kNan;
  g->send(g->odom, o);
  o.pose.pose.position.x = sim->odom.pose.pose.position.x;
  o.header.stamp.fromSec(t / 2);
  g->send(g->odom, o);
  o.header.stamp.fromSec(t / 3);
  g->send(g->odom, o);
  cases += 3;
  // Detections: non-finite positions, an absurd position, a huge stamp.
  hameritt::Detection d;
  d.client = "hostile";
  d.header.frame_id = "map";
  d.header.stamp.fromSec(t);
  d.entity_class = "car";
  d.position.x = kNan;
  g->send(g->detections, d);
  d.position.x = 0;
  d.position.y = kInf;
  g->send(g->detections, d);
  cases += 2;
  // Ground truth (a stamp cannot be non-finite) with a non-finite pose:
  hameritt::EntityStateArray bad_truth;
  bad_truth.header.stamp.fromSec(t);
  bad_truth.entities.resize(1);
  bad_truth.entities[0].id = "car_nan";
  bad_truth.entities[0].pose.position.x = kNan;
  g->send(g->truth, bad_truth);
  // Boxes of an entity that does not exist.
  hameritt::BoundingBoxArray b;
  b.header.stamp.fromSec(t);
  b.boxes.resize(3);
  for (auto& box : b.boxes) {
    box.entity_id = "no_such_entity";
    box.visible_pixels = 1000;
  }
  g->send(g->boxes, b);
  // A mission for another scenario.
  ASSERT_TRUE(g->missions.waitFor(1, 10)) << "no /mission from the adk";
  hameritt::Mission m = g->missions.last();
  m.scenario_id = "area_search-ffffffffffffffff";
  g->send(g->mission, m);
  g->send(g->mission, m);
  cases += 4;
  EXPECT_EQ(g->rosout.errors("/adk", {"/uav/odom", "expected finite"}), 1)
      << g->rosout.dump("/adk");
  EXPECT_EQ(g->rosout.errors("/adk", {"/uav/odom", "header.stamp", "older than the last"}), 1);
  EXPECT_EQ(g->rosout.errors("/adk", {"/perception/detections", "hostile", "finite"}), 1);
  EXPECT_EQ(g->rosout.errors("/adk", {"boxes[].entity_id 'no_such_entity'"}), 1);
  EXPECT_EQ(g->rosout.errors("/adk", {"/ground_truth/entities", "entities[0] 'car_nan'", "finite"}),
            1);
  EXPECT_EQ(g->rosout.errors("/planner", {"/uav/odom", "pose.pose.position.x"}), 1)
      << g->rosout.dump("/planner");
  for (const char* client : {"/coverage_search_client", "/color_shape_detector"}) {
    EXPECT_EQ(g->rosout.errors(client, {"/mission: scenario_id: expected", "ffffffffffffffff"}), 1)
        << client << ": " << g->rosout.dump(client);
  }

  // Everyone alive; the ADK still scores a valid claim and publishes its state.
  fly(500);
  const std::size_t before = g->states.all.size();
  d.position.x = sim->odom.pose.pose.position.x;
  d.position.y = sim->odom.pose.pose.position.y;
  d.position.z = 0;
  d.header.stamp.fromSec(sim->last_time);
  g->send(g->detections, d);
  EXPECT_TRUE(spinUntil([] { return !g->scores.all.empty(); }, 10)) << "no score for a valid claim";
  EXPECT_TRUE(spinUntil([&] { return g->states.all.size() > before; }, 5));
  EXPECT_EQ(g->states.last().state, "running") << g->states.last().reason;
  for (const char* node :
       {"/simulator", "/planner", "/adk", "/coverage_search_client", "/color_shape_detector"}) {
    EXPECT_TRUE(alive(node)) << node;
  }
  EXPECT_EQ(g->badSample(), "");

  // The tally of the three tests above: 4 fields x 3 non-finite velocities, 3 axes x 3
  // non-finite poses, 2 foreign frames, an absurd velocity, an absurd pose and an absurd step
  // (simulator); 6 bad plan requests and 4 bad waypoint lists (planner); 3 odometry, 2
  // detections, a ground truth, a box list and 2 missions (ADK and clients).
  EXPECT_EQ(cases, (4 * 3 + 3 * 3 + 2 + 3) + (6 + 4) + (3 + 2 + 4));
  // badSample() checked the simulator's odometry: at least the samples fly() counted, derived
  // from the publish rate and the steps of each call.
  std::size_t samples = 0;
  for (const auto& o : g->flight.all) samples += o.child_frame_id != "hostile";
  double rate = 0;
  ASSERT_TRUE(ros::param::get("/simulator/publish_rate_hz", rate));
  EXPECT_GE(static_cast<double>(samples), guaranteed_samples);
  EXPECT_GT(guaranteed_samples, 0.0);
  std::printf(
      "hostile_inputs: %d hostile messages and requests sent, %zu odometry samples checked "
      "(%.0f guaranteed by the calls; %.0f Hz x %.3f sim s = %.0f published)\n",
      cases, samples, guaranteed_samples, rate, sim->last_time, rate * sim->last_time);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "hostile_inputs_test");
  Graph graph;
  hameritt::testing::SimClient client;
  g = &graph;
  sim = &client;
  return RUN_ALL_TESTS();
}
