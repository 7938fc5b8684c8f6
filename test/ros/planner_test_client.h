#pragma once
// Shared by the planner rostests: sends waypoints to the follower, records the flight from
// odometry, and checks it against the mission's keep-out zones with the geometry core alone.

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>

#include <string>
#include <vector>

#include "hameritt/CrashEvent.h"
#include "hameritt/FollowProgress.h"
#include "hameritt/SetPaused.h"
#include "hameritt/StepSimulation.h"
#include "hameritt/geometry/polygon.h"
#include "hameritt/scenario/mission_io.h"

namespace hameritt::testing {

struct Sample {
  double t;
  geometry::Vec3 p;
};

class FollowerClient {
 public:
  FollowerClient() {
    odom_sub_ = nh_.subscribe("/uav/odom", 2000, &FollowerClient::onOdom, this);
    progress_sub_ = nh_.subscribe("/planner/progress", 100, &FollowerClient::onProgress, this);
    crash_sub_ = nh_.subscribe("/uav/crash", 10, &FollowerClient::onCrash, this);
    waypoints_pub_ = nh_.advertise<nav_msgs::Path>("/planner/waypoints", 1, true);
  }

  // The simulator starts paused (simulator.launch start_paused:=true) so that sim time does not
  // depend on how long this process takes to start: steps once for an odometry message, waits
  // for the follower to listen, and returns the UAV's start.
  geometry::Vec3 connect() {
    EXPECT_TRUE(ros::service::waitForService("/simulator/step", ros::Duration(60)));
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(60);
    while ((odom_sub_.getNumPublishers() == 0 || waypoints_pub_.getNumSubscribers() == 0) &&
           ros::WallTime::now() < until) {
      ros::WallDuration(0.01).sleep();
    }
    hameritt::StepSimulation step;
    step.request.steps = 1;
    EXPECT_TRUE(ros::service::call("/simulator/step", step)) << "step";
    while (flight.empty() && ros::WallTime::now() < until) {
      ros::spinOnce();
      ros::WallDuration(0.01).sleep();
    }
    EXPECT_FALSE(flight.empty()) << "no odometry";
    return flight.empty() ? geometry::Vec3::Zero() : flight.back().p;
  }

  // Sends the waypoints, waits until the follower has planned, then lets time run.
  void send(const std::vector<geometry::Vec3>& waypoints) {
    nav_msgs::Path path;
    path.header.frame_id = "map";
    for (const auto& w : waypoints) {
      geometry_msgs::PoseStamped p;
      p.header.frame_id = "map";
      p.pose.position.x = w.x();
      p.pose.position.y = w.y();
      p.pose.position.z = w.z();
      p.pose.orientation.w = 1.0;
      path.poses.push_back(p);
    }
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(60);
    // The planner answers "failed: no odometry yet" when its odometry subscription connected
    // after the one step connect() took (the simulator is paused): step once more, so that it
    // publishes odometry again, and send the waypoints again.
    bool sent = false;
    while (!sent || (progress.state == "failed" &&
                     progress.message.rfind("no odometry", 0) == 0 && ros::WallTime::now() < until)) {
      if (sent) {
        hameritt::StepSimulation step;
        step.request.steps = 1;
        EXPECT_TRUE(ros::service::call("/simulator/step", step)) << "step";
        ros::WallDuration(0.1).sleep();
      }
      progress.state.clear();
      waypoints_pub_.publish(path);
      sent = true;
      while (progress.state != "following" && progress.state != "failed" &&
             ros::WallTime::now() < until) {
        ros::spinOnce();
        ros::WallDuration(0.005).sleep();
      }
    }
    hameritt::SetPaused run;
    run.request.paused = false;
    EXPECT_TRUE(ros::service::call("/simulator/set_paused", run)) << "resume";
  }

  // Spins until the follower reports done or failed, or the wall-clock limit passes.
  std::string waitForEnd(double wall_seconds) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(wall_seconds);
    while (ros::WallTime::now() < until && ros::ok()) {
      ros::spinOnce();
      if (progress.state == "done" || progress.state == "failed") break;
      ros::WallDuration(0.002).sleep();
    }
    return progress.state;
  }

  // Keep-out zone violations of the recorded flight: a sample inside a zone's polygon, within
  // its altitude band, while its window is active (segments between 250 Hz samples are under
  // 5 cm at flight speed).
  std::vector<std::string> violations(const scenario::Mission& mission) const {
    std::vector<std::string> out;
    for (const auto& k : mission.kozs) {
      for (const auto& s : flight) {
        if (!k.window.active(s.t)) continue;
        if (k.alt_min && s.p.z() < *k.alt_min) continue;
        if (k.alt_max && s.p.z() > *k.alt_max) continue;
        if (k.polygon.contains(s.p.head<2>())) {
          out.push_back(k.id + " at t=" + std::to_string(s.t));
          break;
        }
      }
    }
    return out;
  }

  // Closest approach of the recorded flight to a point.
  double closest(const geometry::Vec3& w) const {
    double best = 1e18;
    for (const auto& s : flight) best = std::min(best, (s.p - w).norm());
    return best;
  }

  std::vector<Sample> flight;
  hameritt::FollowProgress progress;
  std::vector<hameritt::CrashEvent> crashes;
  std::vector<std::string> messages;  // non-empty progress messages, in order
  unsigned max_replans = 0;

 private:
  void onOdom(const nav_msgs::Odometry::ConstPtr& m) {
    flight.push_back({m->header.stamp.toSec(), geometry::Vec3(m->pose.pose.position.x,
                                                              m->pose.pose.position.y,
                                                              m->pose.pose.position.z)});
  }
  void onProgress(const hameritt::FollowProgress::ConstPtr& m) {
    progress = *m;
    if (!m->message.empty()) messages.push_back(m->message);
    max_replans = std::max(max_replans, m->replans);
  }
  void onCrash(const hameritt::CrashEvent::ConstPtr& m) { crashes.push_back(*m); }

  ros::NodeHandle nh_;
  ros::Subscriber odom_sub_, progress_sub_, crash_sub_;
  ros::Publisher waypoints_pub_;
};

}  // namespace hameritt::testing
