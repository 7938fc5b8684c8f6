#pragma once
// A lock-step client of the simulator node for rostests: pauses it, steps it, and collects the
// messages published for each step.

#include <gtest/gtest.h>
#include <ros/ros.h>

#include <nav_msgs/Odometry.h>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>

#include "hameritt/CrashEvent.h"
#include "hameritt/EntityStateArray.h"
#include "hameritt/ResetSimulation.h"
#include "hameritt/SetPaused.h"
#include "hameritt/StepSimulation.h"

namespace hameritt::testing {

class SimClient {
 public:
  SimClient() {
    odom_sub_ = nh_.subscribe("/uav/odom", 1000, &SimClient::onOdom, this);
    truth_sub_ = nh_.subscribe("/ground_truth/entities", 100, &SimClient::onTruth, this);
    crash_sub_ = nh_.subscribe("/uav/crash", 10, &SimClient::onCrash, this);
    pose_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("/uav/cmd_pose", 10, true);
    vel_pub_ = nh_.advertise<geometry_msgs::Twist>("/uav/cmd_vel", 10, true);
  }

  // Waits for the node's services and subscriptions; pauses and resets it.
  void connect() {
    ASSERT_TRUE(ros::service::waitForService("/simulator/step", ros::Duration(60)));
    ASSERT_TRUE(ros::service::waitForService("/simulator/set_paused", ros::Duration(10)));
    hameritt::SetPaused p;
    p.request.paused = true;
    ASSERT_TRUE(ros::service::call("/simulator/set_paused", p));
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(10);
    while ((pose_pub_.getNumSubscribers() == 0 || vel_pub_.getNumSubscribers() == 0 ||
            odom_sub_.getNumPublishers() == 0) && ros::WallTime::now() < until) {
      ros::WallDuration(0.01).sleep();
    }
    reset();
  }

  // Resets the node to t = 0 and waits for the state it publishes then (a caller that reads
  // `odom` right after must see the reset pose, not a default or earlier one). The state of a
  // reset can be published before this client's connection to the node is up (a test that
  // publishes odometry itself counts as a publisher already): then it resets again.
  void reset() {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(15);
    bool got = false;
    while (!got && ros::WallTime::now() < until) {
      have_odom = have_truth = false;
      hameritt::ResetSimulation r;
      ASSERT_TRUE(ros::service::call("/simulator/reset", r));
      ASSERT_TRUE(r.response.success);
      const ros::WallTime wait = ros::WallTime::now() + ros::WallDuration(0.5);
      while (!got && ros::WallTime::now() < wait) {
        ros::spinOnce();
        ros::WallDuration(0.0005).sleep();
        got = have_odom && odom.header.stamp.toSec() == 0.0 && have_truth &&
              truth.header.stamp.toSec() == 0.0;
      }
    }
    ASSERT_TRUE(got) << "no odometry and ground truth at t = 0 within 15 s of resetting";
    crashes.clear();
    drain();
  }

  // Sends a pose setpoint and makes sure the node has it before the next step.
  void setPose(double x, double y, double z, double yaw) {
    geometry_msgs::PoseStamped m;
    m.header.frame_id = "map";
    m.pose.position.x = x;
    m.pose.position.y = y;
    m.pose.position.z = z;
    m.pose.orientation.z = std::sin(0.5 * yaw);
    m.pose.orientation.w = std::cos(0.5 * yaw);
    pose_pub_.publish(m);
    settle();
  }

  void setVelocity(double vx, double vy, double vz, double yaw_rate) {
    geometry_msgs::Twist m;
    m.linear.x = vx;
    m.linear.y = vy;
    m.linear.z = vz;
    m.angular.z = yaw_rate;
    vel_pub_.publish(m);
    settle();
  }

  // Advances `steps` physics steps; returns the odometry published at the end.
  nav_msgs::Odometry step(unsigned steps) {
    hameritt::StepSimulation s;
    s.request.steps = steps;
    EXPECT_TRUE(ros::service::call("/simulator/step", s));
    EXPECT_TRUE(s.response.success) << s.response.message;
    last_time = s.response.sim_time;
    // The node publishes the state at the end of the call; wait until it arrives.
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(10);
    while (ros::WallTime::now() < until &&
           !(have_odom && std::abs(odom.header.stamp.toSec() - last_time) < 1e-6 && have_truth &&
             std::abs(truth.header.stamp.toSec() - last_time) < 1e-6)) {
      ros::spinOnce();
      ros::WallDuration(0.0005).sleep();
    }
    EXPECT_NEAR(odom.header.stamp.toSec(), last_time, 1e-6);
    return odom;
  }

  nav_msgs::Odometry odom;
  hameritt::EntityStateArray truth;
  std::vector<hameritt::CrashEvent> crashes;
  bool have_odom = false, have_truth = false;
  double last_time = 0;

 private:
  void settle() {
    // Latched publisher plus a short wait so that the node's queue holds the message.
    ros::WallDuration(0.05).sleep();
    drain();
  }
  void drain() {
    for (int i = 0; i < 20; ++i) {
      ros::spinOnce();
      ros::WallDuration(0.001).sleep();
    }
  }
  void onOdom(const nav_msgs::Odometry::ConstPtr& m) {
    odom = *m;
    have_odom = true;
  }
  void onTruth(const hameritt::EntityStateArray::ConstPtr& m) {
    truth = *m;
    have_truth = true;
  }
  void onCrash(const hameritt::CrashEvent::ConstPtr& m) { crashes.push_back(*m); }

  ros::NodeHandle nh_;
  ros::Subscriber odom_sub_, truth_sub_, crash_sub_;
  ros::Publisher pose_pub_, vel_pub_;
};

}  // namespace hameritt::testing
