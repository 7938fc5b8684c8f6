#include "hameritt/ros/planner_ros.h"

#include <geometry_msgs/PoseStamped.h>

#include <algorithm>
#include <cmath>

#include "hameritt/FollowProgress.h"
#include "hameritt/planning/follow.h"
#include "hameritt/planning/request_checks.h"
#include "hameritt/ros/conversions.h"
#include "hameritt/ros/log_throttle.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/scenario/sim_config_io.h"

namespace hameritt::ros_wrappers {

namespace {

planning::UavAlgorithm parseAlgorithm(const std::string& name) {
  if (name == "rrt_connect" || name.empty()) return planning::UavAlgorithm::kRrtConnect;
  if (name == "rrt_star") return planning::UavAlgorithm::kRrtStar;
  throw scenario::ConfigError("algorithm: expected rrt_connect or rrt_star, got '" + name + "'");
}

geometry::Vec3 toVec(const geometry_msgs::Point& p) { return {p.x, p.y, p.z}; }

}  // namespace

PlannerRos::PlannerRos(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  gate_ = std::make_unique<LockstepGate>(nh, pnh);
  std::string mission_path, sim_path, algorithm;
  if (!pnh.getParam("mission", mission_path)) {
    throw scenario::ConfigError("~mission: required parameter (path of a mission.json)");
  }
  if (!pnh.getParam("sim_config", sim_path)) {
    throw scenario::ConfigError("~sim_config: required parameter (path of a sim_config.json)");
  }
  double margin = 1.0, rate = 10.0;
  int seed = 1;
  pnh.param("margin", margin, margin);
  pnh.param("rate_hz", rate, rate);
  pnh.param("lookahead", lookahead_, lookahead_);
  pnh.param("acceptance_radius", acceptance_, acceptance_);
  pnh.param("koz_horizon", koz_horizon_, koz_horizon_);
  pnh.param("max_deviation", max_deviation_, max_deviation_);
  pnh.param("carrot_clearance", clearance_, clearance_);
  pnh.param("seed", seed, seed);
  pnh.param<std::string>("algorithm", algorithm, "rrt_connect");
  seed_ = static_cast<std::uint64_t>(seed);
  if (!(rate > 0 && rate <= 200)) throw scenario::ConfigError("~rate_hz: expected (0, 200]");
  if (!(lookahead_ >= 0 && lookahead_ <= 10)) throw scenario::ConfigError("~lookahead: expected [0, 10] s");
  if (!(acceptance_ > 0)) throw scenario::ConfigError("~acceptance_radius: expected > 0");
  if (!(koz_horizon_ >= 0)) throw scenario::ConfigError("~koz_horizon: expected >= 0");
  if (!(max_deviation_ > acceptance_)) {
    throw scenario::ConfigError("~max_deviation: expected more than ~acceptance_radius");
  }

  mission_ = scenario::loadMission(mission_path);
  sim_ = scenario::loadSimConfig(sim_path);
  if (mission_.scenario_id != sim_.scenario_id) {
    throw scenario::ConfigError(mission_path + ": scenario_id: '" + mission_.scenario_id +
                                "' does not match " + sim_path + " ('" + sim_.scenario_id + "')");
  }
  world_ = std::make_unique<scenario::World>(scenario::generateCheckedWorld(sim_, sim_path));
  validity_settings_ = planning::validitySettingsFor(sim_.uav, margin);
  validity_settings_.validate();
  if (!(clearance_ > 0 && clearance_ <= margin)) {
    throw scenario::ConfigError("~carrot_clearance: expected metres in (0, ~margin = " +
                                scenario::formatNumber(margin) + "], got " +
                                scenario::formatNumber(clearance_));
  }
  settings_.algorithm = parseAlgorithm(algorithm);
  settings_.speed.max_speed = sim_.uav.max_speed;
  settings_.validate();
  full_validity_ = std::make_unique<planning::WorldValidity>(*world_, mission_, validity_settings_);

  setpoint_pub_ = gate_->advertise<geometry_msgs::PoseStamped>(nh, "uav/cmd_pose", 10);
  path_pub_ = gate_->advertise<nav_msgs::Path>(pnh, "path", 1, true);
  progress_pub_ = gate_->advertise<hameritt::FollowProgress>(pnh, "progress", 10, true);
  odom_sub_ = gate_->subscribe(nh, "uav/odom", 10, &PlannerRos::onOdometry, this);
  waypoints_sub_ = gate_->subscribe(pnh, "waypoints", 1, &PlannerRos::onWaypoints, this);
  plan_srv_ = pnh.advertiseService("plan_path", &PlannerRos::onPlan, this);
  gate_->every(nh, 1.0 / rate, [this] { onTick(); });
  publishProgress("idle", "waiting for waypoints on " + waypoints_sub_.getTopic());
  ROS_INFO("planner: %s, %zu keep-out zones, altitude %.0f..%.0f m", mission_.scenario_id.c_str(),
           mission_.kozs.size(), validity_settings_.altitude_min, validity_settings_.altitude_max);
}

bool PlannerRos::onPlan(hameritt::PlanPath::Request& req, hameritt::PlanPath::Response& res) {
  try {
    planning::UavPlannerSettings s = settings_;
    s.algorithm = parseAlgorithm(req.algorithm);
    std::vector<geometry::Vec3> points;
    for (const auto& w : req.waypoints) points.push_back(toVec(w));
    std::string error = planning::checkPoint(toVec(req.start), "start");
    if (error.empty()) error = planning::checkWaypoints(points, "waypoints");
    if (error.empty() && !std::isfinite(req.start_time)) {
      error =
          "start_time: expected a finite time (s), got " + scenario::formatNumber(req.start_time);
    }
    if (!error.empty()) throw scenario::ConfigError(error);
    points.insert(points.begin(), toVec(req.start));
    const planning::PlanResult r =
        planning::planUavWaypoints(*full_validity_, points, req.start_time, s, req.seed);
    res.success = r.ok();
    res.code = r.ok() ? 0 : 1;
    res.status = planning::toString(r.status);
    res.message = r.message;
    res.path = toPathMsg(r.path, ros::Time::now());
    res.length = r.length;
    res.duration = r.path.empty() ? 0.0 : r.path.back().t - r.path.front().t;
  } catch (const std::exception& e) {
    res.success = false;
    res.code = 2;
    res.status = "invalid_request";
    res.message = e.what();
  }
  return true;
}

void PlannerRos::onOdometry(const nav_msgs::Odometry::ConstPtr& msg) {
  const std::string error =
      planning::checkPoint(toVec(msg->pose.pose.position), "pose.pose.position");
  if (!error.empty()) {
    HAMERITT_ERROR_THROTTLE(5.0, "planner: %s: %s; ignored", odom_sub_.getTopic().c_str(),
                            error.c_str());
    return;
  }
  odom_ = *msg;
  have_odom_ = true;
}

std::vector<scenario::KeepOutZone> PlannerRos::committedZones(double t) const {
  std::vector<scenario::KeepOutZone> out;
  for (const auto& k : mission_.kozs) {
    const bool ended = k.window.nlt && *k.window.nlt < t;
    const bool soon = !k.window.net || *k.window.net <= t + koz_horizon_;
    if (!ended && soon) out.push_back(k);
  }
  return out;
}

void PlannerRos::onWaypoints(const nav_msgs::Path::ConstPtr& msg) {
  // Hostile lists are refused whole, the path being flown is kept; an empty list stops.
  std::vector<geometry::Vec3> points;
  for (const auto& p : msg->poses) points.push_back(toVec(p.pose.position));
  std::string error;
  if (!msg->header.frame_id.empty() && msg->header.frame_id != kMapFrame) {
    error = "header.frame_id: expected '" + std::string(kMapFrame) + "' (or empty), got '" +
            msg->header.frame_id + "'";
  } else if (!points.empty()) {
    error = planning::checkWaypoints(points, "poses");
  }
  if (!error.empty()) {
    HAMERITT_ERROR_THROTTLE(5.0, "planner: %s: %s; ignored", waypoints_sub_.getTopic().c_str(),
                            error.c_str());
    return;
  }
  waypoints_ = std::move(points);
  next_waypoint_ = 0;
  replans_ = 0;
  path_.clear();
  if (waypoints_.empty()) {
    active_ = false;
    publishProgress("idle", "empty waypoint list");
    return;
  }
  if (!have_odom_) {
    active_ = false;
    publishProgress("failed", "no odometry on " + odom_sub_.getTopic() + " yet");
    return;
  }
  active_ = replan(ros::Time::now().toSec(), "new waypoints");
}

bool PlannerRos::replan(double t, const std::string& why) {
  const auto& p = odom_.pose.pose.position;
  geometry::Vec3 here(p.x, p.y, p.z);
  scenario::Trajectory prefix;
  // Below the flight band (on the ground, taking off): climb straight up into it first.
  const double floor = validity_settings_.altitude_min + validity_settings_.margin + 0.5;
  if (here.z() < floor) {
    const double climb_t = (floor - here.z()) / settings_.speed.climb_rate;
    prefix.push_back({t, here.x(), here.y(), here.z(), 0.0});
    here.z() = floor;
    t += climb_t;
  }
  std::vector<geometry::Vec3> legs{here};
  for (std::size_t i = next_waypoint_; i < waypoints_.size(); ++i) legs.push_back(waypoints_[i]);
  const auto zones = committedZones(t);
  const planning::WorldValidity validity(*world_, zones, validity_settings_);
  const planning::PlanResult r = planning::planUavWaypoints(
      validity, legs, t, settings_, scenario::deriveSeed(seed_, plans_++));
  if (!r.ok()) {
    path_.clear();
    publishProgress("failed", why + ": " + planning::toString(r.status) + ": " + r.message);
    ROS_WARN("planner: %s: %s", why.c_str(), r.message.c_str());
    return false;
  }
  path_ = prefix;
  path_.insert(path_.end(), r.path.begin(), r.path.end());
  arc_.assign(1, 0.0);
  for (std::size_t i = 1; i < path_.size(); ++i) {
    arc_.push_back(arc_.back() + std::hypot(std::hypot(path_[i].x - path_[i - 1].x,
                                                       path_[i].y - path_[i - 1].y),
                                            path_[i].z - path_[i - 1].z));
  }
  progress_ = 0.0;
  committed_.clear();
  for (const auto& k : zones) committed_.insert(k.id);
  if (why != "new waypoints") ++replans_;
  gate_->publish(path_pub_, toPathMsg(path_, ros::Time::now()));
  publishProgress("following", why + ": planned " + std::to_string(r.path.size()) + " samples");
  ROS_INFO("planner: %s: %s path of %.1f m", why.c_str(), planning::toString(r.status), r.length);
  return true;
}

void PlannerRos::onTick() {
  if (!active_ || !have_odom_ || path_.empty()) return;
  const double t = ros::Time::now().toSec();
  const auto& p = odom_.pose.pose.position;
  const geometry::Vec3 here(p.x, p.y, p.z);
  if ((here - waypoints_[next_waypoint_]).norm() < acceptance_) {
    ++next_waypoint_;
    if (next_waypoint_ == waypoints_.size()) {
      active_ = false;
      publishProgress("done", "all waypoints reached");
      return;
    }
  }
  // Project the UAV on the path near its last progress: cross-track distance and the plan time
  // at that point.
  double best = 1e18, best_s = progress_, plan_t = path_.front().t;
  for (std::size_t i = 0; i + 1 < path_.size(); ++i) {
    if (arc_[i + 1] < progress_ - 5.0) continue;
    if (arc_[i] > progress_ + 60.0) break;
    const geometry::Vec3 a(path_[i].x, path_[i].y, path_[i].z);
    const geometry::Vec3 b(path_[i + 1].x, path_[i + 1].y, path_[i + 1].z);
    const double len2 = (b - a).squaredNorm();
    const double u = len2 > 0 ? std::clamp((here - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
    const double d = (a + u * (b - a) - here).norm();
    if (d < best) {
      best = d;
      best_s = arc_[i] + u * (arc_[i + 1] - arc_[i]);
      plan_t = path_[i].t + u * (path_[i + 1].t - path_[i].t);
    }
  }
  progress_ = std::max(progress_, best_s);
  if (best > max_deviation_) {
    if (!replan(t, "off the path by " + std::to_string(best) + " m")) active_ = false;
    return;
  }
  // The rest of the path as the UAV will actually fly it: shifted by its lag behind the plan.
  const double lag = t - plan_t;
  scenario::Trajectory rest;
  for (const auto& q : path_) {
    if (q.t > plan_t) rest.push_back({q.t + lag, q.x, q.y, q.z, q.yaw});
  }
  rest.insert(rest.begin(), {t, here.x(), here.y(), here.z(), 0.0});
  const auto zones = committedZones(t);
  std::string opening;
  for (const auto& k : zones) {
    if (!committed_.count(k.id)) opening += (opening.empty() ? "" : ", ") + k.id;
  }
  // Static obstacles do not move, so only the keep-out zones are re-checked, exactly.
  const planning::WorldValidity validity(*world_, zones, validity_settings_);
  bool blocked = false;
  for (std::size_t i = 0; i + 1 < rest.size() && !blocked; ++i) {
    const geometry::Vec3 a(rest[i].x, rest[i].y, rest[i].z);
    const geometry::Vec3 b(rest[i + 1].x, rest[i + 1].y, rest[i + 1].z);
    blocked = !validity.kozSegmentClear(a, b, rest[i].t, rest[i + 1].t);
  }
  if (blocked) {
    const std::string why = opening.empty()
                                ? "the rest of the path, " + std::to_string(lag) +
                                      " s behind schedule, meets a keep-out zone"
                                : "keep-out zone " + opening + " opens across the path";
    if (!replan(t, why)) active_ = false;
    return;
  }
  for (const auto& k : zones) committed_.insert(k.id);
  // The carrot, pulled back along the path until the line to it clears the buildings.
  const double carrot_t =
      planning::clearCarrotTime(*full_validity_, path_, here, plan_t, lookahead_, clearance_);
  const scenario::TrajectoryPoint sp = scenario::sampleTrajectory(path_, carrot_t);
  gate_->publish(setpoint_pub_, toPoseMsg(sp, ros::Time::now()));
  publishProgress("following", "");
}

void PlannerRos::publishProgress(const std::string& state, const std::string& message) {
  hameritt::FollowProgress m;
  m.header.stamp = ros::Time::now();
  m.header.frame_id = kMapFrame;
  m.state = state;
  m.waypoint = static_cast<std::uint32_t>(next_waypoint_);
  m.waypoints = static_cast<std::uint32_t>(waypoints_.size());
  if (have_odom_ && next_waypoint_ < waypoints_.size()) {
    const auto& p = odom_.pose.pose.position;
    m.distance_to_waypoint = (geometry::Vec3(p.x, p.y, p.z) - waypoints_[next_waypoint_]).norm();
  }
  m.replans = replans_;
  m.message = message;
  gate_->publish(progress_pub_, m);
}

}  // namespace hameritt::ros_wrappers
