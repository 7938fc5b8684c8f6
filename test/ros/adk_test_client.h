#pragma once
// Helpers of the ADK rostests: the test node plays the simulator (it publishes /clock,
// odometry, ground truth, camera boxes and crashes) and collects what the adk node publishes.

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include <Eigen/Core>
#include <cmath>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hameritt::testing {

// A JSON file the ADK wrote; an empty object (and a test failure) when it cannot be read.
inline nlohmann::json readJsonFile(const std::string& path) {
  std::ifstream f(path);
  EXPECT_TRUE(f.good()) << path << ": cannot read";
  if (!f.good()) return nlohmann::json::object();
  return nlohmann::json::parse(f);
}

// Serves callbacks until `done` holds or `seconds` of wall time have passed; returns done().
inline bool spinUntil(const std::function<bool()>& done, double seconds) {
  const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::WallTime::now() < until) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.002).sleep();
  }
  ros::spinOnce();
  return done();
}

// Keeps the messages of one topic.
template <class M>
class Collector {
 public:
  Collector(ros::NodeHandle& nh, const std::string& topic, int queue = 1000) {
    sub_ =
        nh.subscribe<M>(topic, queue, [this](const typename M::ConstPtr& m) { all.push_back(*m); });
  }
  bool connected() const { return sub_.getNumPublishers() > 0; }
  bool waitFor(std::size_t n, double seconds) {
    return spinUntil([&] { return all.size() >= n; }, seconds);
  }
  const M& last() const { return all.back(); }
  std::vector<M> all;

 private:
  ros::Subscriber sub_;
};

// Sim time and odometry for one or more namespaces of adk nodes.
class FakeSimulator {
 public:
  explicit FakeSimulator(ros::NodeHandle& nh, const std::vector<std::string>& namespaces = {""}) {
    clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 1000);
    for (const auto& ns : namespaces) {
      odom_pubs_.push_back(nh.advertise<nav_msgs::Odometry>(ns + "/uav/odom", 5000));
    }
  }

  // Waits until every odometry topic and /clock has `n` subscribers (the adk nodes).
  bool waitForSubscribers(double seconds, unsigned n = 1) {
    return spinUntil(
        [&] {
          if (clock_pub_.getNumSubscribers() < n) return false;
          for (const auto& p : odom_pubs_) {
            if (p.getNumSubscribers() < 1) return false;
          }
          return true;
        },
        seconds);
  }

  // The time as the adk node will read it (nanosecond stamps).
  static double quantized(double t) {
    ros::Time s;
    s.fromSec(t);
    return s.toSec();
  }

  // Publishes odometry at (t, p, v) on every namespace, then the clock.
  void publish(double t, const Eigen::Vector3d& p, const Eigen::Vector3d& v) {
    for (std::size_t i = 0; i < odom_pubs_.size(); ++i) publishOdometry(i, t, p, v);
    clock(t);
  }

  // Odometry at (t, p, v) on the i-th namespace only, without the clock: for flights that
  // differ per node (publish the clock after every namespace's odometry of the step).
  void publishOdometry(std::size_t i, double t, const Eigen::Vector3d& p,
                       const Eigen::Vector3d& v) {
    nav_msgs::Odometry o;
    o.header.stamp.fromSec(t);
    o.header.frame_id = "map";
    o.child_frame_id = "uav/base_link";
    o.pose.pose.position.x = p.x();
    o.pose.pose.position.y = p.y();
    o.pose.pose.position.z = p.z();
    o.pose.pose.orientation.w = 1.0;  // heading east: body velocity = world velocity
    o.twist.twist.linear.x = v.x();
    o.twist.twist.linear.y = v.y();
    o.twist.twist.linear.z = v.z();
    odom_pubs_.at(i).publish(o);
  }

  void clock(double t) {
    rosgraph_msgs::Clock c;
    c.clock.fromSec(t);
    clock_pub_.publish(c);
  }

 private:
  ros::Publisher clock_pub_;
  std::vector<ros::Publisher> odom_pubs_;
};

}  // namespace hameritt::testing
