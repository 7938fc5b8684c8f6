// rostest: the coverage search client flies the shipped scenario's search through the real
// planner and simulator (it reaches the first area of interest inside its window and sweeps part
// of it, clear of keep-out zones, without a crash), and in maneuver-only mode turns a perfect
// perception report into one claim for the target, none for a look-alike, and then hovers.
#include "hameritt/build_paths.h"
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>

#include <algorithm>

#include "hameritt/CrashEvent.h"
#include "hameritt/Detection.h"
#include "hameritt/FollowProgress.h"
#include "hameritt/PerceptionReport.h"
#include "hameritt/SetPaused.h"
#include "hameritt/StepSimulation.h"
#include "hameritt/ros/mission_conversions.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/sim_config_io.h"

namespace {

using hameritt::geometry::Vec2;
using hameritt::geometry::Vec3;

const std::string kScenario = std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/";

struct Sample {
  double t;
  Vec3 p;
};

// Plays the ADK and records what the clients and the UAV do.
class Observer {
 public:
  Observer() {
    mission_ = hameritt::scenario::loadMission(kScenario + "mission.json");
    mission_pub_ = nh_.advertise<hameritt::Mission>("/mission", 1, true);
    report_pub_ = nh_.advertise<hameritt::PerceptionReport>("/adk/perfect_perception", 10);
    odom_sub_ = nh_.subscribe("/uav/odom", 5000, &Observer::onOdom, this);
    wp_sub_ = nh_.subscribe("/planner/waypoints", 100, &Observer::onWaypoints, this);
    progress_sub_ = nh_.subscribe("/planner/progress", 500, &Observer::onProgress, this);
    det_sub_ = nh_.subscribe("/perception/detections", 100, &Observer::onDetection, this);
    crash_sub_ = nh_.subscribe("/uav/crash", 10, &Observer::onCrash, this);
  }

  void spinFor(double wall) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(wall);
    while (ros::ok() && ros::WallTime::now() < until) {
      ros::spinOnce();
      ros::WallDuration(0.002).sleep();
    }
  }
  template <typename Pred>
  bool spinUntil(Pred done, double wall) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(wall);
    while (ros::ok() && ros::WallTime::now() < until) {
      ros::spinOnce();
      if (done()) return true;
      ros::WallDuration(0.002).sleep();
    }
    return done();
  }

  hameritt::scenario::Mission mission_;
  std::vector<Sample> flight;
  std::vector<nav_msgs::Path> waypoints;
  std::vector<hameritt::FollowProgress> progress;
  std::vector<hameritt::Detection> detections;
  std::vector<hameritt::CrashEvent> crashes;
  ros::NodeHandle nh_;
  ros::Publisher mission_pub_, report_pub_;
  ros::Subscriber odom_sub_, wp_sub_, progress_sub_, det_sub_, crash_sub_;

 private:
  void onOdom(const nav_msgs::Odometry::ConstPtr& m) {
    const auto& p = m->pose.pose.position;
    flight.push_back({m->header.stamp.toSec(), Vec3(p.x, p.y, p.z)});
  }
  void onWaypoints(const nav_msgs::Path::ConstPtr& m) { waypoints.push_back(*m); }
  void onProgress(const hameritt::FollowProgress::ConstPtr& m) { progress.push_back(*m); }
  void onDetection(const hameritt::Detection::ConstPtr& m) { detections.push_back(*m); }
  void onCrash(const hameritt::CrashEvent::ConstPtr& m) { crashes.push_back(*m); }
};

Observer* observer = nullptr;

TEST(Clients, CoverageSearchReachesTheFirstAreaAndSweepsItThroughThePlanner) {
  Observer& o = *observer;
  o.mission_pub_.publish(hameritt::ros_wrappers::toMsg(o.mission_));
  // The simulator starts paused: one step gives everybody odometry, the client plans and sends
  // its first leg, the follower plans it; then time runs (5x real time).
  ASSERT_TRUE(ros::service::waitForService("/simulator/step", ros::Duration(60)));
  ASSERT_TRUE(ros::service::waitForService("/planner/plan_path", ros::Duration(60)));
  ASSERT_TRUE(o.spinUntil([&] { return o.wp_sub_.getNumPublishers() > 0; }, 60.0))
      << "coverage_search_client is not up";
  // Step until the client has odometry and answers with waypoints: its odometry subscription
  // may connect a moment after it advertises, and a paused simulator publishes nothing between
  // steps, so a single step can go unheard on a loaded machine.
  hameritt::StepSimulation step;
  step.request.steps = 1;
  for (int i = 0; i < 60 && o.waypoints.empty(); ++i) {
    ASSERT_TRUE(ros::service::call("/simulator/step", step));
    o.spinUntil([&] { return !o.waypoints.empty(); }, 1.0);
  }
  ASSERT_FALSE(o.waypoints.empty()) << "the client sent no waypoints";
  o.spinUntil(
      [&] {
        return std::any_of(o.progress.begin(), o.progress.end(), [](const auto& p) {
          return p.state == "following" || p.state == "failed";
        });
      },
      30.0);
  hameritt::SetPaused run;
  run.request.paused = false;
  ASSERT_TRUE(ros::service::call("/simulator/set_paused", run));

  // Until 100 s of mission time: aoi_1 opens at 48 s and lies ~500 m away.
  const auto& aoi = o.mission_.aois.front();
  ASSERT_EQ(aoi.id, "aoi_1");
  o.spinUntil([&] { return !o.flight.empty() && o.flight.back().t >= 100.0; }, 100.0);
  ASSERT_FALSE(o.flight.empty());
  EXPECT_GE(o.flight.back().t, 100.0) << "sim time did not get far enough";

  // The UAV reached the first area inside its window and swept part of it at search altitude.
  double inside = 0.0, first_in = -1.0;
  for (std::size_t i = 1; i < o.flight.size(); ++i) {
    const Vec3& p = o.flight[i].p;
    if (aoi.polygon.contains(p.head<2>()) && aoi.window.active(o.flight[i].t) && p.z() > 20.0) {
      if (first_in < 0) first_in = o.flight[i].t;
      inside += (p - o.flight[i - 1].p).norm();
    }
  }
  EXPECT_GE(first_in, 48.0);
  EXPECT_GE(inside, 60.0) << "metres flown inside aoi_1 during its window";
  // Legs of the search: the follower finished at least one, and the client sent the next.
  const auto done = std::count_if(o.progress.begin(), o.progress.end(),
                                  [](const auto& p) { return p.state == "done"; });
  EXPECT_GE(done, 1);
  EXPECT_GE(o.waypoints.size(), 2u);
  // Every waypoint the client sent is outside the keep-out zones (all are always active here).
  for (const auto& path : o.waypoints) {
    for (const auto& w : path.poses) {
      const Vec3 p(w.pose.position.x, w.pose.position.y, w.pose.position.z);
      for (const auto& k : o.mission_.kozs) {
        if ((k.alt_min && p.z() < *k.alt_min) || (k.alt_max && p.z() > *k.alt_max)) continue;
        EXPECT_FALSE(k.polygon.contains(p.head<2>())) << k.id << " " << p.transpose();
      }
    }
  }
  // And the flight never entered one.
  for (const auto& k : o.mission_.kozs) {
    for (const auto& s : o.flight) {
      if ((k.alt_min && s.p.z() < *k.alt_min) || (k.alt_max && s.p.z() > *k.alt_max)) continue;
      if (!k.window.active(s.t)) continue;
      ASSERT_FALSE(k.polygon.contains(s.p.head<2>())) << k.id << " at t=" << s.t;
    }
  }
  EXPECT_TRUE(o.crashes.empty());
  EXPECT_TRUE(o.detections.empty());
}

TEST(Clients, ManeuverOnlyClaimsTheTargetFromPerfectPerceptionAndThenHovers) {
  Observer& o = *observer;
  ASSERT_FALSE(o.flight.empty());
  // Ground truth is the ADK's to give: the target and a look-alike confuser in aoi_1.
  const auto truth = hameritt::scenario::loadSimConfig(kScenario + "sim_config.json");
  hameritt::PerceptionReport report;
  report.header.stamp = ros::Time::now();
  report.header.frame_id = "uav/camera_front_optical";
  report.camera = "front";
  for (const char* id : {"car_706", "car_722"}) {
    for (const auto& e : truth.entities) {
      if (e.entity.id != id) continue;
      hameritt::PerceivedEntity pe;
      pe.entity_id = e.entity.id;
      pe.entity_class = "car";
      pe.role = e.role;
      for (const auto& [k, v] : e.entity.attributes.items) {
        hameritt::KeyValue kv;
        kv.key = k;
        kv.value = std::get<std::string>(v);
        pe.attributes.push_back(kv);
      }
      const Vec3 p = e.entity.position();
      pe.position.x = p.x();
      pe.position.y = p.y();
      pe.position.z = p.z();
      pe.yaw = e.entity.yaw();
      report.entities.push_back(pe);
    }
  }
  ASSERT_EQ(report.entities.size(), 2u);
  ASSERT_TRUE(o.spinUntil([&] { return o.report_pub_.getNumSubscribers() > 0; }, 10.0));
  const std::size_t paths_before = o.waypoints.size();
  o.report_pub_.publish(report);
  ASSERT_TRUE(o.spinUntil([&] { return !o.detections.empty(); }, 20.0)) << "no claim";
  o.report_pub_.publish(report);  // the same frame again: no second claim
  o.spinFor(1.0);
  ASSERT_EQ(o.detections.size(), 1u);
  const auto& d = o.detections.front();
  EXPECT_EQ(d.client, "coverage_search_client");
  EXPECT_EQ(d.description, "white Toyota RAV4 (suv)");
  EXPECT_NEAR(d.position.x, report.entities[0].position.x, 1e-6);
  EXPECT_NEAR(d.position.y, report.entities[0].position.y, 1e-6);
  EXPECT_GT(d.confidence, 0.5);
  EXPECT_EQ(d.header.stamp, report.header.stamp);
  // The objective's one target is found: the client hovers where the UAV is.
  ASSERT_TRUE(o.spinUntil([&] { return o.waypoints.size() > paths_before; }, 10.0));
  const nav_msgs::Path& hover = o.waypoints.back();
  ASSERT_EQ(hover.poses.size(), 1u);
  const Vec3 h(hover.poses[0].pose.position.x, hover.poses[0].pose.position.y,
               hover.poses[0].pose.position.z);
  EXPECT_LT((h - o.flight.back().p).head<2>().norm(), 15.0);
  EXPECT_TRUE(o.crashes.empty());
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "clients_test");
  Observer o;
  observer = &o;
  const int r = RUN_ALL_TESTS();
  observer = nullptr;
  return r;
}
