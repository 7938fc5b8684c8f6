#pragma once
// ROS wrapper of the planning library: the PlanPath service and a waypoint follower that turns
// a client's sparse waypoints into a keep-out-zone-respecting flight, tracks it with pose
// setpoints to the simulator, and replans when the rest of its path becomes blocked.

#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>

#include <memory>
#include <set>
#include <string>
#include <vector>

#include "hameritt/PlanPath.h"
#include "hameritt/planning/uav_planner.h"
#include "hameritt/planning/validity.h"
#include "hameritt/ros/lockstep.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::ros_wrappers {

// Parameters (private): ~mission, ~sim_config (paths, required), ~margin (1.0 m),
// ~algorithm (rrt_connect | rrt_star), ~rate_hz (10), ~lookahead (1.5 s: the setpoint is the
// planned point this far, in plan time, ahead of the UAV's progress along the path, pulled back
// to 3/4, 1/2, 1/4 or 1/8 of it while the straight line to it passes nearer than
// ~carrot_clearance (0.5 m, at most ~margin) to an obstacle: planning/follow.h),
// ~acceptance_radius (2.0 m), ~koz_horizon (15 s: the follower commits to keep-out zones active
// now or opening within this many seconds), ~max_deviation (6 m: farther than this from the path
// is "blocked"), ~seed.
//
// Each tick the follower projects the UAV onto its path (progress and cross-track distance),
// shifts the rest of the path by how far behind or ahead of schedule the UAV is, and replans
// from where the UAV is when that shifted path meets a committed keep-out zone while it is
// active (a zone opening inside the horizon, or delays), or when the UAV is off the path.
class PlannerRos {
 public:
  // Throws scenario::ConfigError for bad parameters or files (the node exits with ROS_FATAL).
  PlannerRos(ros::NodeHandle& nh, ros::NodeHandle& pnh);
  // Serves callbacks until shutdown (in turns when ~lockstep).
  void spin() { gate_->spin(); }

 private:
  bool onPlan(hameritt::PlanPath::Request& req, hameritt::PlanPath::Response& res);
  void onOdometry(const nav_msgs::Odometry::ConstPtr& msg);
  void onWaypoints(const nav_msgs::Path::ConstPtr& msg);
  void onTick();
  // Keep-out zones the follower commits to at time t: active now or opening within the horizon.
  std::vector<scenario::KeepOutZone> committedZones(double t) const;
  bool replan(double t, const std::string& why);
  void publishProgress(const std::string& state, const std::string& message);

  scenario::Mission mission_;
  scenario::SimConfig sim_;
  // First, destroyed last: the subscriptions and the tick go through it.
  std::unique_ptr<LockstepGate> gate_;
  std::unique_ptr<scenario::World> world_;
  planning::ValiditySettings validity_settings_;
  std::unique_ptr<planning::WorldValidity> full_validity_;
  planning::UavPlannerSettings settings_;
  double lookahead_ = 1.5, acceptance_ = 2.0, koz_horizon_ = 15.0, max_deviation_ = 6.0;
  double clearance_ = 0.5;
  std::uint64_t seed_ = 1;

  bool have_odom_ = false;
  nav_msgs::Odometry odom_;
  std::vector<geometry::Vec3> waypoints_;
  std::size_t next_waypoint_ = 0;
  scenario::Trajectory path_;
  std::vector<double> arc_;  // arc length at each path sample
  double progress_ = 0.0;    // arc length of the UAV's projection on the path
  std::set<std::string> committed_;  // ids of the zones the current path was planned against
  unsigned replans_ = 0;
  bool active_ = false;
  std::uint64_t plans_ = 0;

  ros::Publisher setpoint_pub_, path_pub_, progress_pub_;
  ros::Subscriber odom_sub_, waypoints_sub_;
  ros::ServiceServer plan_srv_;
};

}  // namespace hameritt::ros_wrappers
