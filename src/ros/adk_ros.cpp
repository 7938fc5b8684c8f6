#include "hameritt/ros/adk_ros.h"

#include <ros/callback_queue.h>
#include <sys/statvfs.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "hameritt/AvoidStatus.h"
#include "hameritt/ConstraintEvent.h"
#include "hameritt/ConstraintStatus.h"
#include "hameritt/DetectionScore.h"
#include "hameritt/Mission.h"
#include "hameritt/MissionMetrics.h"
#include "hameritt/MissionState.h"
#include "hameritt/PerceptionReport.h"
#include "hameritt/UavSpec.h"
#include "hameritt/ros/adk_conversions.h"
#include "hameritt/ros/log_throttle.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/sim_config_io.h"

namespace hameritt::ros_wrappers {

namespace {

std::atomic<bool> g_stop{false};

// The period of an optional report's rate parameter ~NAME in [0, 100] Hz (0: off, period 0).
double optionalPeriod(ros::NodeHandle& pnh, const std::string& name, double default_hz,
                      const std::string& off) {
  double hz = default_hz;
  pnh.param(name, hz, hz);
  if (!(hz >= 0.0 && hz <= 100.0)) {
    throw scenario::ConfigError("~" + name + ": expected [0, 100] (0: " + off + "), got " +
                                scenario::formatNumber(hz));
  }
  return hz > 0.0 ? 1.0 / hz : 0.0;
}

using scenario::ConfigError;

ros::Time stampOf(double t) {
  ros::Time s;
  s.fromSec(std::max(0.0, t));
  return s;
}

}  // namespace

void AdkRos::requestStop() { g_stop = true; }

AdkRos::AdkRos(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  gate_ = std::make_unique<LockstepGate>(nh, pnh);
  std::string mission_path, sim_config_path;
  if (!pnh.getParam("mission", mission_path) || mission_path.empty()) {
    throw ConfigError("~mission: required parameter (path of a mission.json)");
  }
  if (!pnh.getParam("sim_config", sim_config_path) || sim_config_path.empty()) {
    throw ConfigError("~sim_config: required parameter (path of a sim_config.json)");
  }
  pnh.param<std::string>("output_dir", output_dir_, "");
  pnh.param<std::string>("mode", mode_, "maneuver_only");
  if (mode_ != "maneuver_only" && mode_ != "perception_only" && mode_ != "end_to_end") {
    throw ConfigError("~mode: expected maneuver_only, perception_only or end_to_end, got '" +
                      mode_ + "'");
  }
  pnh.param("perfect_perception", perfect_perception_, mode_ == "maneuver_only");
  pnh.param("min_visible_pixels", min_visible_pixels_, 20);
  if (min_visible_pixels_ < 1) {
    throw ConfigError("~min_visible_pixels: expected an integer >= 1, got " +
                      std::to_string(min_visible_pixels_));
  }
  double status_rate = 10.0;
  pnh.param("status_rate_hz", status_rate, status_rate);
  if (!(status_rate > 0.0 && status_rate <= 1000.0)) {
    throw ConfigError("~status_rate_hz: expected a rate in (0, 1000], got " +
                      scenario::formatNumber(status_rate));
  }
  status_period_ = 1.0 / status_rate;
  pnh.param("shutdown_on_end", shutdown_on_end_, true);
  pnh.param("end_linger", end_linger_, 1.0);
  if (!(end_linger_ >= 0.0 && end_linger_ <= 60.0)) {
    throw ConfigError("~end_linger: expected wall seconds in [0, 60], got " +
                      scenario::formatNumber(end_linger_));
  }
  double clock_timeout = 10.0;
  pnh.param("clock_timeout", clock_timeout, clock_timeout);
  if (!(clock_timeout >= 0.0 && clock_timeout <= 3600.0)) {
    throw ConfigError("~clock_timeout: expected wall seconds in [0, 3600] (0 = off), got " +
                      scenario::formatNumber(clock_timeout));
  }
  if (gate_->enabled() && clock_timeout > 0) {
    // In lock-step the clock also waits while another participant takes its turn, which the
    // simulator allows for up to the lock-step timeout: only a longer silence is a stall.
    clock_timeout = std::max(clock_timeout, gate_->timeout() + 10.0);
  }
  watchdog_ = std::make_unique<adk::ClockWatchdog>(clock_timeout);
  adk::ScoringSettings scoring;
  pnh.param("car_gate", scoring.car_gate, scoring.car_gate);
  pnh.param("pedestrian_gate", scoring.pedestrian_gate, scoring.pedestrian_gate);
  adk::ObjectiveSettings objective;
  pnh.param("found_by_sighting", objective.found_by_sighting, mode_ == "maneuver_only");
  found_by_sighting_ = objective.found_by_sighting;
  pnh.param("track_fraction", objective.track_fraction, objective.track_fraction);
  double cell = 2.0;
  pnh.param("coverage_cell_size", cell, cell);
  if (!(cell >= 0.25 && cell <= 100.0)) {
    throw ConfigError("~coverage_cell_size: expected metres in [0.25, 100], got " +
                      scenario::formatNumber(cell));
  }
  pnh.param("coverage_max_range", coverage_max_range_, coverage_max_range_);
  if (!(coverage_max_range_ > 0.0 && coverage_max_range_ <= 5000.0)) {
    throw ConfigError("~coverage_max_range: expected metres in (0, 5000], got " +
                      scenario::formatNumber(coverage_max_range_));
  }

  pnh.param("recorder_min_space_mb", recorder_min_space_mb_, 0.0);
  if (!(recorder_min_space_mb_ >= 0.0 && recorder_min_space_mb_ <= 1e9)) {
    throw ConfigError("~recorder_min_space_mb: expected MB in [0, 1e9] (0 = no recorder), got " +
                      scenario::formatNumber(recorder_min_space_mb_));
  }

  mission_ = scenario::loadMission(mission_path);
  sim_config_ = scenario::loadSimConfig(sim_config_path);
  if (sim_config_.scenario_id != mission_.scenario_id) {
    throw ConfigError(sim_config_path + ": scenario_id: expected '" + mission_.scenario_id +
                      "' (the mission's, " + mission_path + "), got '" + sim_config_.scenario_id +
                      "'");
  }
  double time_limit = mission_.time_limit;
  pnh.param("time_limit", time_limit, time_limit);
  if (!(time_limit > 0.0 && std::isfinite(time_limit))) {
    throw ConfigError("~time_limit: expected seconds > 0, got " +
                      scenario::formatNumber(time_limit));
  }
  world_ = std::make_unique<scenario::World>(
      scenario::generateCheckedWorld(sim_config_, sim_config_path));
  for (std::size_t i = 0; i < sim_config_.entities.size(); ++i) {
    scenario_index_[sim_config_.entities[i].entity.id] = i;
  }
  for (const auto& e : world_->entities()) {
    if (e.cls != scenario::EntityClass::kCar) continue;
    world_car_index_[e.id] = world_cars_.size();
    world_cars_.push_back({e.id, "car", "world", e.position(), e.yaw()});
  }
  for (const auto& c : sim_config_.uav.cameras) {
    intrinsics_.push_back(adk::intrinsicsFromHfov(c.width, c.height, c.hfov_deg));
  }
  next_footprint_t_.assign(sim_config_.uav.cameras.size(), 0.0);

  monitor_ = std::make_unique<adk::ConstraintMonitor>(mission_);
  coverage_ = std::make_unique<adk::CoverageGrid>(mission_, cell);
  scorer_ = std::make_unique<adk::DetectionScorer>(mission_, sim_config_.entities, scoring);
  metrics_ = std::make_unique<adk::MetricsAccumulator>(mission_, objective);
  lifecycle_ = std::make_unique<adk::MissionLifecycle>(time_limit);
  for (const auto& phase : mission_.phases) {
    if (phase.type == scenario::PhaseType::kAvoid) {
      avoid_ = std::make_unique<adk::AvoidScorer>(phase.avoid, time_limit);
      avoid_phase_ = phase.id;
    } else if (phase.type == scenario::PhaseType::kFollow) {
      follow_ = std::make_unique<adk::FollowScorer>(phase);
      const auto it = scenario_index_.find(phase.targets.front());
      if (it == scenario_index_.end()) {
        throw ConfigError(mission_path + ": phase '" + phase.id + "': target '" +
                          phase.targets.front() + "' is not an entity of " + sim_config_path);
      }
      follow_target_ = &sim_config_.entities[it->second];
    } else if (phase.type == scenario::PhaseType::kTrack && !track_) {
      track_ = std::make_unique<adk::TrackScorer>(phase);
      for (const auto& id : phase.targets) {
        if (scenario_index_.count(id) == 0) {
          throw ConfigError(mission_path + ": phase '" + phase.id + "': target '" + id +
                            "' is not an entity of " + sim_config_path);
        }
      }
    } else if (phase.type == scenario::PhaseType::kSearch && !search_phase_) {
      search_phase_ = &phase;
    }
  }

  mission_pub_ = gate_->advertise<hameritt::Mission>(nh, "mission", 1, true);
  markers_pub_ = gate_->advertise<visualization_msgs::MarkerArray>(nh, "mission/markers", 1, true);
  uav_pub_ = gate_->advertise<hameritt::UavSpec>(nh, "mission/uav", 1, true);
  constraints_pub_ = gate_->advertise<hameritt::ConstraintStatus>(nh, "adk/constraints", 10);
  events_pub_ = gate_->advertise<hameritt::ConstraintEvent>(nh, "adk/constraint_events", 100);
  perception_pub_ = gate_->advertise<hameritt::PerceptionReport>(nh, "adk/perfect_perception", 20);
  scores_pub_ = gate_->advertise<hameritt::DetectionScore>(nh, "adk/detection_scores", 100);
  state_pub_ = gate_->advertise<hameritt::MissionState>(nh, "adk/state", 10, true);
  metrics_pub_ = gate_->advertise<hameritt::MissionMetrics>(nh, "adk/metrics", 1, true);
  if (avoid_) avoid_pub_ = gate_->advertise<hameritt::AvoidStatus>(nh, "adk/avoid", 10, true);
  // The ADS-B-like traffic reports of an avoid mission's aircraft.
  traffic_period_ = optionalPeriod(pnh, "traffic_rate_hz", 2.0, "no traffic reports");
  if (avoid_ && traffic_period_ > 0.0) {
    traffic_pub_ = gate_->advertise<hameritt::EntityStateArray>(nh, "adk/traffic", 10);
  }
  if (follow_) follow_pub_ = gate_->advertise<hameritt::FollowStatus>(nh, "adk/follow", 10, true);
  // The found targets' ground-truth state at a tracker's rate: what a maneuver client under test
  // gets in place of a tracker, from the find on (maneuver_only by default).
  target_state_period_ = optionalPeriod(pnh, "target_state_rate_hz",
                                        mode_ == "maneuver_only" ? 10.0 : 0.0, "no target state");
  if (target_state_period_ > 0.0) {
    target_state_pub_ = gate_->advertise<hameritt::EntityStateArray>(nh, "adk/target_state", 20);
  }
  if (track_) {
    if (sim_config_.uav.cameras.empty()) {
      throw ConfigError(sim_config_path + ": uav.cameras: a track mission needs a camera");
    }
    // By default the camera that looks down: the one under a UAV that keeps a car in view from
    // above and behind it (the baseline's pursuit standoff).
    std::string camera = sim_config_.uav.cameras.front().name;
    for (const auto& c : sim_config_.uav.cameras) {
      if (c.name == "down") camera = c.name;
    }
    pnh.param<std::string>("track_camera", camera, camera);
    track_camera_ = sim_config_.uav.cameras.size();
    for (std::size_t i = 0; i < sim_config_.uav.cameras.size(); ++i) {
      if (sim_config_.uav.cameras[i].name == camera) track_camera_ = i;
    }
    if (track_camera_ == sim_config_.uav.cameras.size()) {
      throw ConfigError("~track_camera: expected a camera of " + sim_config_path + ", got '" +
                        camera + "'");
    }
    track_pub_ = gate_->advertise<hameritt::TrackStatus>(nh, "adk/track", 10, true);
  }
  if (!mission_.phases.empty()) {
    phase_pub_ = gate_->advertise<hameritt::PhaseState>(nh, "adk/phase", 10, true);
  }

  if (gate_->enabled()) {
    // Lock-step: the turn carries the sim time (README "Lock-step missions").
    gate_->onTurn([this](const ros::Time& t) {
      auto c = boost::make_shared<rosgraph_msgs::Clock>();
      c->clock = t;
      onClock(c);
    });
  } else {
    clock_sub_ = nh.subscribe("/clock", 10, &AdkRos::onClock, this);
  }
  odom_sub_ = gate_->subscribe(nh, "uav/odom", 1000, &AdkRos::onOdometry, this);
  truth_sub_ = gate_->subscribe(nh, "ground_truth/entities", 100, &AdkRos::onTruth, this);
  crash_sub_ = gate_->subscribe(nh, "uav/crash", 10, &AdkRos::onCrash, this);
  detection_sub_ = gate_->subscribe(nh, "perception/detections", 100, &AdkRos::onDetection, this);
  if (track_) tracks_sub_ = gate_->subscribe(nh, "perception/tracks", 100, &AdkRos::onTracks, this);
  for (std::size_t i = 0; i < sim_config_.uav.cameras.size(); ++i) {
    const std::string topic = "uav/camera/" + sim_config_.uav.cameras[i].name + "/boxes";
    box_subs_.push_back(gate_->subscribe<hameritt::BoundingBoxArray>(
        nh, topic, 20,
        [this, i](const hameritt::BoundingBoxArray::ConstPtr& m) { onBoxes(i, m); }));
  }
  // Last: in lock-step a turn hands it over after the odometry of the same cycle.
  sim_end_sub_ = gate_->subscribe(nh, "simulator/end", 1, &AdkRos::onSimulationEnd, this);
  // The state again every second (wall time; sim time in lock-step), until the mission ends.
  gate_->every(
      nh, 1.0,
      [this] {
        if (!gate_->enabled() || !finished_) publishState();
      },
      /*wall=*/true);

  const ros::Time stamp = stampOf(0.0);
  gate_->publish(mission_pub_, toMsg(mission_, stamp));
  gate_->publish(markers_pub_,
                 missionMarkers(mission_, sim_config_.uav.altitude_max + 20.0, stamp));
  hameritt::UavSpec uav = toMsg(sim_config_.uav, sim_config_.scenario_id);
  uav.header.stamp = stamp;
  gate_->publish(uav_pub_, uav);
  publishState();
  if (!mission_.phases.empty()) {
    publishPhase(0.0, mission_.phases.front(), adk::PhaseState::kActive,
                 "the mission's first phase");
  }
  ROS_INFO(
      "adk: %s (%s), mode %s, perfect perception %s, time limit %.1f s, %zu cameras, "
      "metrics to %s",
      mission_.scenario_id.c_str(), mission_.objective.type.c_str(), mode_.c_str(),
      perfect_perception_ ? "on" : "off", time_limit, intrinsics_.size(),
      output_dir_.empty() ? "(not written)" : (output_dir_ + "/metrics.json").c_str());
}

std::vector<adk::EntityTruth> AdkRos::truthAt(double t) const {
  std::vector<adk::EntityTruth> out;
  if (!truth_.empty()) {
    out = truth_.at(t);
  } else {
    for (const auto& e : sim_config_.entities) out.push_back(adk::scenarioEntityAt(e, t));
  }
  out.insert(out.end(), world_cars_.begin(), world_cars_.end());
  return out;
}

void AdkRos::publishState() {
  hameritt::MissionState s;
  s.header.stamp = stampOf(now_);
  s.state = adk::toString(lifecycle_->state());
  s.mode = mode_;
  s.elapsed = lifecycle_->ended() ? lifecycle_->endTime() : now_;
  s.time_limit = lifecycle_->timeLimit();
  s.reason = lifecycle_->reason();
  gate_->publish(state_pub_, s);
}

void AdkRos::publishConstraints(double t) {
  gate_->publish(constraints_pub_, toMsg(*monitor_, stampOf(t)));
}

void AdkRos::onClock(const rosgraph_msgs::Clock::ConstPtr& msg) {
  if (finished_) return;
  const double t = msg->clock.toSec();
  const bool was_late = watchdog_->lateStart() >= 0;
  watchdog_->clock(t, ros::WallTime::now().toSec());
  if (!was_late && watchdog_->lateStart() >= 0) {
    ROS_WARN(
        "adk: started in a mission under way (first sim time %.3f s): the metrics will "
        "cover only what happens from now on",
        watchdog_->lateStart());
  }
  now_ = std::max(now_, t);
  // While odometry flows, it drives the start and the time limit, so that the metrics include
  // the sample at the limit (the simulator publishes the clock before the odometry of a step);
  // the clock alone decides without odometry or when it has stalled for a second.
  if (have_odom_ && t - last_odom_t_ <= 1.0) return;
  judgeTrackAtLimit(t);
  if (lifecycle_->update(t, have_odom_)) {
    publishState();
    if (lifecycle_->ended()) finish();
  }
}

void AdkRos::onOdometry(const nav_msgs::Odometry::ConstPtr& msg) {
  if (finished_) return;
  const double t = msg->header.stamp.toSec();
  if (have_odom_ && !(t > last_odom_t_)) {
    // The simulator publishes the state twice at a step it was asked for; a time going back is
    // a reset, which a mission run does not do.
    if (t < last_odom_t_) {
      HAMERITT_ERROR_THROTTLE(5.0,
                              "adk: %s: header.stamp %.6f s is older than the last (%.6f s); "
                              "ignored (was the simulator reset?)",
                              odom_sub_.getTopic().c_str(), t, last_odom_t_);
    }
    return;
  }
  const Eigen::Isometry3d pose = poseOf(*msg);
  const Eigen::Vector3d p = pose.translation();
  if (track_) poses_.add(t, pose);
  const Eigen::Vector3d v = worldVelocityOf(*msg);
  try {
    for (const auto& e : monitor_->add(t, p)) gate_->publish(events_pub_, toMsg(e));
    metrics_->addState(t, p, v);
    if (avoid_) {
      const adk::TrafficSample sample = avoidSample(t, p, v);
      avoid_->add(sample);
      if (traffic_period_ > 0.0 && t >= next_traffic_t_) {
        publishTraffic(t, sample);
        next_traffic_t_ = t + traffic_period_;
      }
    }
    if (follow_ && follow_->started()) {
      const adk::EntityTruth target = adk::scenarioEntityAt(*follow_target_, t);
      adk::FollowSample f;
      f.t = t;
      f.vehicle = p;
      f.target = target.position;
      f.target_yaw = target.yaw;
      // The sight line from the UAV to the middle of the car, past buildings, trees, fences
      // and parked cars.
      f.line_of_sight =
          world_->occluders().clear(p, target.position + Eigen::Vector3d(0.0, 0.0, 0.75));
      follow_->add(f);
    }
  } catch (const adk::InputError& e) {
    HAMERITT_ERROR_THROTTLE(5.0, "adk: %s: %s; ignored", odom_sub_.getTopic().c_str(), e.what());
    return;
  }
  have_odom_ = true;
  last_odom_t_ = t;
  now_ = std::max(now_, t);
  for (std::size_t c = 0; c < intrinsics_.size(); ++c) {
    if (t < next_footprint_t_[c]) continue;
    const auto& cam = sim_config_.uav.cameras[c];
    coverage_->addFootprint(
        adk::groundFootprint(intrinsics_[c], adk::opticalPose(pose, cam), coverage_max_range_), t);
    next_footprint_t_[c] = t + 1.0 / cam.rate_hz;
  }
  if (t >= next_status_t_) {
    publishConstraints(t);
    if (avoid_) publishAvoid(t, avoid_->score(monitor_->violationDuration()));
    if (follow_ && follow_->started()) publishFollow(t, followScore(false));
    if (track_ && track_->started()) publishTrack(t, track_->status());
    next_status_t_ = t + status_period_;
  }
  judgeTrackAtLimit(t);
  if (lifecycle_->update(t, true)) {
    publishState();
    if (lifecycle_->ended()) finish();
  }
  // A target found before the mission started running ends it as soon as it runs.
  checkObjective(t);
  checkAvoid(t);
  checkFollow(t);
  checkTrack(t);
  endAtSimulationEnd(false);
}

void AdkRos::onSimulationEnd(const hameritt::SimulationEnd::ConstPtr& msg) {
  if (finished_ || sim_end_pending_) return;
  sim_end_pending_ = true;
  sim_end_t_ = msg->header.stamp.toSec();
  sim_end_reason_ = msg->reason;
  sim_end_seen_ = ros::WallTime::now();
  ROS_INFO("adk: the simulator stopped at sim time %.3f s (%s): ending the mission", sim_end_t_,
           sim_end_reason_.c_str());
  endAtSimulationEnd(false);
}

void AdkRos::endAtSimulationEnd(bool force) {
  if (!sim_end_pending_ || finished_) return;
  // Free running, the last odometry may arrive just after the end message.
  if (!force && have_odom_ && last_odom_t_ < sim_end_t_ - 1e-6) return;
  sim_end_pending_ = false;
  now_ = std::max(now_, sim_end_t_);
  // A time limit reached at the same sim time is the mission's own end: it goes first.
  if (!lifecycle_->update(sim_end_t_, have_odom_) || !lifecycle_->ended()) {
    lifecycle_->simulationEnded(sim_end_t_, sim_end_reason_);
  }
  publishState();
  finish();
}

std::string AdkRos::recorderDiskShortage() const {
  if (recorder_min_space_mb_ <= 0 || output_dir_.empty()) return "";
  // The disk of the output directory (of its nearest existing parent, before it is made).
  struct statvfs st {};
  std::filesystem::path dir = std::filesystem::absolute(output_dir_);
  while (::statvfs(dir.c_str(), &st) != 0) {
    if (dir == dir.parent_path()) return "";
    dir = dir.parent_path();
  }
  // As rosbag's recorder judges it (--min-space against the space available to it).
  const double free_mb = static_cast<double>(st.f_bavail) * st.f_frsize / (1024.0 * 1024.0);
  if (free_mb >= recorder_min_space_mb_) return "";
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "recorder stopped: less than %g MB free on the output disk (%.1f MB free in %s)",
                recorder_min_space_mb_, free_mb, output_dir_.c_str());
  return buf;
}

void AdkRos::onTruth(const hameritt::EntityStateArray::ConstPtr& msg) {
  try {
    truth_.add(msg->header.stamp.toSec(), fromMsg(*msg));
  } catch (const adk::InputError& e) {
    HAMERITT_ERROR_THROTTLE(5.0, "adk: %s: %s; ignored", truth_sub_.getTopic().c_str(), e.what());
    return;
  }
  publishTargetState(*msg);
}

void AdkRos::publishTargetState(const hameritt::EntityStateArray& truth) {
  const double t = truth.header.stamp.toSec();
  if (target_state_period_ <= 0.0 || finished_ || t + 1e-9 < next_target_state_t_ ||
      lifecycle_->state() != adk::MissionState::kRunning) {
    return;
  }
  hameritt::EntityStateArray m;
  m.header = truth.header;
  for (const auto& tm : metrics_->targets()) {
    if (!tm.found) continue;
    for (const auto& e : truth.entities) {
      if (e.id == tm.id) m.entities.push_back(e);
    }
  }
  if (m.entities.empty()) return;     // nothing found yet
  if (next_target_state_t_ <= 0.0) {  // the first message: at the grid's next point
    next_target_state_t_ = std::ceil(t / target_state_period_ - 1e-6) * target_state_period_;
    if (t + 1e-9 < next_target_state_t_) return;
  }
  // On the rate's grid of sim time, whatever the ground truth's own rate.
  next_target_state_t_ = (std::floor(t / target_state_period_ + 1e-6) + 1.0) * target_state_period_;
  gate_->publish(target_state_pub_, m);
}

void AdkRos::onCrash(const hameritt::CrashEvent::ConstPtr& msg) {
  if (finished_) return;
  const double t = msg->header.stamp.toSec();
  char buf[160];
  std::snprintf(buf, sizeof(buf), "crashed into %s at %.2f m/s", msg->entity_id.c_str(),
                msg->speed);
  crashed_ = true;
  if (lifecycle_->crash(std::max(t, 0.0), buf)) {
    publishState();
    finish();
  }
}

void AdkRos::judgeTrackAtLimit(double t) {
  if (lifecycle_->state() != adk::MissionState::kRunning || !metrics_->isTrack() || follow_ ||
      track_) {
    return;  // follow and track missions are judged by their phases (checkFollow, checkTrack)
  }
  const double limit = lifecycle_->timeLimit();
  if (t < limit || !metrics_->objectiveMet(limit)) return;  // else the time limit: timeout
  const std::string how = metrics_->targets().size() == 1 ? "the target" : "every target";
  if (lifecycle_->succeed(t, how + " in view for the track fraction of the time limit")) {
    publishState();
    finish();
  }
}

std::optional<std::string> AdkRos::phaseStartsAtFind(double t, bool started,
                                                     const scenario::MissionPhase& phase) {
  if (lifecycle_->state() != adk::MissionState::kRunning || started) return std::nullopt;
  const auto& targets = metrics_->targets();
  if (!std::all_of(targets.begin(), targets.end(), [](const auto& tm) { return tm.found; })) {
    return std::nullopt;
  }
  const std::string noun = targets.size() == 1 ? "target" : "targets";
  const std::string how = noun + (found_by_sighting_ ? " sighted" : " claimed");
  if (search_phase_) publishPhase(t, *search_phase_, adk::PhaseState::kSucceeded, how);
  publishPhase(t, phase, adk::PhaseState::kActive, how);
  return how;
}

void AdkRos::checkObjective(double t) {
  // The search phase ends at the find: the track or follow phase starts.
  if (track_) {
    if (const auto how = phaseStartsAtFind(t, track_->started(), track_->phase())) {
      track_->start(t);
      ROS_INFO("adk: %s at t = %.3f s: the track phase '%s' starts (%.0f s)", how->c_str(), t,
               track_->phase().id.c_str(), *track_->phase().duration);
    }
    return;
  }
  if (follow_) {
    if (const auto how = phaseStartsAtFind(t, follow_->started(), follow_->phase())) {
      follow_->start(t);
      follow_koz_start_ = monitor_->violationDuration();
      ROS_INFO(
          "adk: %s at t = %.3f s: the follow phase '%s' starts (approach up to %g s, then "
          "%.0f s scored)",
          how->c_str(), t, follow_->phase().id.c_str(), follow_->phase().follow.approach_s,
          *follow_->phase().duration);
    }
    return;
  }
  if (lifecycle_->state() != adk::MissionState::kRunning || metrics_->isTrack()) return;
  if (!metrics_->objectiveMet(t)) return;
  // Says how the targets were found: sighted by a camera (~found_by_sighting) or claimed.
  const std::string how = metrics_->targets().size() == 1 ? "target" : "every target";
  if (lifecycle_->succeed(
          t, how + (found_by_sighting_ ? " sighted" : " correctly claimed by the client"))) {
    publishState();
    finish();
  }
}

adk::TrafficSample AdkRos::avoidSample(double t, const Eigen::Vector3d& p,
                                       const Eigen::Vector3d& v) const {
  adk::TrafficSample s;
  s.t = t;
  s.position = p;
  s.velocity = v;
  // The aircraft fly scripted trajectories (sim_config.json): their ground truth at t, the
  // velocity from the trajectory over +-0.05 s.
  for (const auto& a : sim_config_.aircraft) {
    const auto at = [&](double u) {
      const scenario::TrajectoryPoint q = scenario::sampleTrajectory(a.trajectory, u);
      return Eigen::Vector3d(q.x, q.y, q.z);
    };
    adk::AircraftState st;
    st.id = a.id;
    st.position = at(t);
    st.velocity = (at(t + 0.05) - at(t - 0.05)) / 0.1;
    s.aircraft.push_back(st);
  }
  return s;
}

void AdkRos::publishTraffic(double t, const adk::TrafficSample& s) {
  hameritt::EntityStateArray m;
  m.header.stamp = stampOf(t);
  m.header.frame_id = "map";
  for (std::size_t i = 0; i < s.aircraft.size(); ++i) {
    const auto& a = s.aircraft[i];
    const auto& spec = sim_config_.aircraft[i];
    hameritt::EntityState e;
    e.header = m.header;
    e.id = a.id;
    e.entity_class = "aircraft";
    e.role = "aircraft";
    // The message's pose is the bottom of the box; the report's position is the body centre.
    e.pose.position.x = a.position.x();
    e.pose.position.y = a.position.y();
    e.pose.position.z = a.position.z() - 0.5 * spec.size.z();
    const double yaw = std::atan2(a.velocity.y(), a.velocity.x());
    e.pose.orientation.z = std::sin(0.5 * yaw);
    e.pose.orientation.w = std::cos(0.5 * yaw);
    e.velocity.linear.x = a.velocity.x();
    e.velocity.linear.y = a.velocity.y();
    e.velocity.linear.z = a.velocity.z();
    e.size.x = spec.size.x();
    e.size.y = spec.size.y();
    e.size.z = spec.size.z();
    m.entities.push_back(e);
  }
  gate_->publish(traffic_pub_, m);
}

void AdkRos::publishAvoid(double t, const adk::AvoidScore& a) {
  hameritt::AvoidStatus m;
  m.header.stamp = stampOf(t);
  m.header.frame_id = "map";
  m.phase = avoid_phase_;
  m.reached = a.reach_time.has_value();
  m.reach_time = a.reach_time ? *a.reach_time : std::nan("");
  m.goal_distance = a.goal_distance_m;
  m.path_length = a.path_length_m;
  m.separation_lost = avoid_->separationLost();
  m.min_separation = a.separation.min_distance_m;
  m.closest_aircraft = a.separation.closest_aircraft;
  m.seconds_below_minimum = a.separation.seconds_below_minimum;
  m.separation_losses = static_cast<std::uint32_t>(a.separation.losses);
  m.min_time_to_collision = a.separation.min_time_to_collision_s;
  m.contact = a.separation.contact;
  m.koz_seconds = a.koz_seconds;
  gate_->publish(avoid_pub_, m);
}

void AdkRos::checkAvoid(double t) {
  if (!avoid_ || !avoid_->reached() || lifecycle_->state() != adk::MissionState::kRunning) return;
  const adk::AvoidScore s = avoid_->score(monitor_->violationDuration());
  char at[64];
  std::snprintf(at, sizeof(at), "reached the goal at t = %.3f s", *s.reach_time);
  for (const auto& phase : mission_.phases) {
    if (phase.id != avoid_phase_) continue;
    publishPhase(t, phase, s.success ? adk::PhaseState::kSucceeded : adk::PhaseState::kFailed,
                 s.success ? std::string(at) : s.failure);
  }
  if (s.success ? lifecycle_->succeed(t, at)
                : lifecycle_->fail(t, std::string(at) + ", but " + s.failure)) {
    publishState();
    finish();
  }
}

adk::FollowPhaseScore AdkRos::followScore(bool ended) const {
  const double koz = follow_->started() ? monitor_->violationDuration() - follow_koz_start_ : 0.0;
  return follow_->score(koz, crashed_, ended);
}

void AdkRos::publishFollow(double t, const adk::FollowPhaseScore& f) {
  hameritt::FollowStatus m;
  m.header.stamp = stampOf(t);
  m.header.frame_id = "map";
  m.phase = f.phase;
  m.target = f.target;
  m.state = adk::toString(f.state);
  m.start_time = f.start_time ? *f.start_time : std::nan("");
  m.approach_time = f.approach_time;
  m.duration = f.duration;
  m.elapsed = f.elapsed;
  m.outside = f.outside;
  m.current_outside = f.current_outside_s;
  m.inside_fraction = f.envelope.inside_fraction;
  m.longest_outside = f.envelope.longest_outside_s;
  m.rms_distance_error = f.envelope.rms_distance_error_m;
  m.p95_distance_error = f.envelope.p95_distance_error_m;
  m.rms_height_error = f.envelope.rms_height_error_m;
  m.line_of_sight_fraction = f.envelope.line_of_sight_fraction;
  m.koz_seconds = f.koz_seconds;
  m.failure = f.failure;
  gate_->publish(follow_pub_, m);
}

void AdkRos::publishPhase(double t, const scenario::MissionPhase& phase, adk::PhaseState state,
                          const std::string& reason) {
  hameritt::PhaseState m;
  m.header.stamp = stampOf(t);
  m.phase = phase.id;
  m.type = scenario::toString(phase.type);
  m.state = adk::toString(state);
  m.reason = reason;
  phase_states_[phase.id] = state;
  gate_->publish(phase_pub_, m);
}

void AdkRos::checkFollow(double t) {
  if (!follow_ || !follow_->started() || lifecycle_->state() != adk::MissionState::kRunning) {
    return;
  }
  if (!follow_->complete() && !follow_->failedEarly() &&
      monitor_->violationDuration() - follow_koz_start_ <= 0.0) {
    return;
  }
  const adk::FollowPhaseScore f = followScore(true);
  publishPhase(t, follow_->phase(), f.state, f.success ? "criteria met" : f.failure);
  if (f.success ? lifecycle_->succeed(t, "the follow phase '" + f.phase + "' succeeded")
                : lifecycle_->fail(t, "the follow phase '" + f.phase + "' failed: " + f.failure)) {
    publishState();
    finish();
  }
}

void AdkRos::publishTrack(double t, const adk::TrackPhaseScore& s) {
  hameritt::TrackStatus m;
  m.header.stamp = stampOf(t);
  m.phase = s.phase;
  m.targets = s.targets;
  m.state = adk::toString(s.state);
  m.start_time = s.start_time ? *s.start_time : std::nan("");
  m.duration = s.duration;
  m.elapsed = s.elapsed;
  m.frames = static_cast<std::uint32_t>(s.frames);
  m.reports = static_cast<std::uint32_t>(s.reports);
  m.tracked_fraction = s.tracked_fraction;
  m.current_break = s.current_break_s;
  m.errors_unknown_id = static_cast<std::uint32_t>(s.errors.unknown_id);
  m.errors_bad_box = static_cast<std::uint32_t>(s.errors.bad_box);
  m.errors_duplicate_id = static_cast<std::uint32_t>(s.errors.duplicate_id);
  m.errors_out_of_order = static_cast<std::uint32_t>(s.errors.out_of_order);
  m.errors_unmatched_stamp = static_cast<std::uint32_t>(s.errors.unmatched_stamp);
  m.failure = s.failure;
  gate_->publish(track_pub_, m);
}

void AdkRos::checkTrack(double t) {
  if (!track_ || !track_->started() || lifecycle_->state() != adk::MissionState::kRunning) {
    return;
  }
  if (!track_->complete() && !track_->failedEarly()) return;
  const adk::TrackPhaseScore s = track_->score(true);
  publishPhase(t, track_->phase(), s.state, s.success ? "criteria met" : s.failure);
  if (s.success ? lifecycle_->succeed(t, "the track phase '" + s.phase + "' succeeded")
                : lifecycle_->fail(t, "the track phase '" + s.phase + "' failed: " + s.failure)) {
    publishState();
    finish();
  }
}

void AdkRos::addTrackFrame(const hameritt::BoundingBoxArray& msg) {
  std::vector<adk::TargetTruth> targets;
  for (const auto& b : msg.boxes) {
    const auto& ids = track_->phase().targets;
    if (std::find(ids.begin(), ids.end(), b.entity_id) == ids.end() || b.total_pixels == 0) {
      continue;
    }
    adk::TargetTruth g;
    g.id = b.entity_id;
    // The bounds of the visible pixels (the renderer's box; x_max, y_max inclusive).
    g.box = adk::PixelBox{static_cast<double>(b.x_min), static_cast<double>(b.y_min),
                          static_cast<double>(b.x_max - b.x_min + 1),
                          static_cast<double>(b.y_max - b.y_min + 1)};
    g.visible_fraction =
        std::clamp(static_cast<double>(b.visible_pixels) / b.total_pixels, 0.0, 1.0);
    g.occlusion = std::clamp(static_cast<double>(b.occlusion), 0.0, 1.0);
    targets.push_back(g);
  }
  const double stamp = msg.header.stamp.toSec();
  // The targets without a box: hidden in the camera's view (occlusion level full) or out of it.
  // Without the UAV's pose at the frame (no odometry within 0.5 s) they stay out of the frame.
  const auto base = poses_.at(stamp, 0.5);
  if (!base) {
    HAMERITT_ERROR_THROTTLE(5.0,
                            "adk: camera %s: no odometry within 0.5 s of the frame at %.3f s: "
                            "its targets without a box count as out of view",
                            msg.camera.c_str(), stamp);
  } else {
    std::vector<adk::TargetExtent> extents;
    for (const auto& e : truthAt(stamp)) {
      const auto& ids = track_->phase().targets;
      const auto s = scenario_index_.find(e.id);
      if (s == scenario_index_.end() || std::find(ids.begin(), ids.end(), e.id) == ids.end()) {
        continue;
      }
      const auto& size = sim_config_.entities[s->second].entity.box.size;
      extents.push_back({e.id, scenario::boxFromPose(e.position, e.yaw, size)});
    }
    const auto& cam = sim_config_.uav.cameras[track_camera_];
    targets = adk::withHiddenTargets(std::move(targets), extents, intrinsics_[track_camera_],
                                     adk::opticalPose(*base, cam));
  }
  try {
    track_->addFrame(stamp, targets);
  } catch (const adk::InputError& e) {
    HAMERITT_ERROR_THROTTLE(5.0, "adk: camera %s: %s; ignored", msg.camera.c_str(), e.what());
  }
}

void AdkRos::onTracks(const hameritt::TrackReport::ConstPtr& msg) {
  if (finished_ || !track_) return;
  const auto& cam = sim_config_.uav.cameras[track_camera_];
  std::vector<adk::ReportedTrack> tracks;
  for (const auto& b : msg->tracks)
    tracks.push_back({b.target_id, adk::PixelBox{b.x, b.y, b.w, b.h}});
  // Reports of the other cameras are not scored (nor errors): the phase is one camera's.
  if (msg->camera != cam.name) return;
  track_->addReport(msg->header.stamp.toSec(), tracks);
}

void AdkRos::onBoxes(std::size_t camera, const hameritt::BoundingBoxArray::ConstPtr& msg) {
  if (finished_) return;
  if (track_ && camera == track_camera_ && track_->started()) addTrackFrame(*msg);
  const auto& cam = sim_config_.uav.cameras[camera];
  const double stamp = msg->header.stamp.toSec();
  hameritt::PerceptionReport report;
  report.header = msg->header;
  report.camera = cam.name;
  std::vector<adk::EntityTruth> truth;
  bool have_truth = false;
  for (const auto& box : msg->boxes) {
    if (box.visible_pixels < static_cast<std::uint32_t>(min_visible_pixels_)) continue;
    hameritt::PerceivedEntity pe;
    pe.entity_id = box.entity_id;
    pe.box = box;
    const auto s = scenario_index_.find(box.entity_id);
    const auto w = world_car_index_.find(box.entity_id);
    adk::EntityTruth where;
    if (s != scenario_index_.end()) {
      if (!have_truth) {
        truth = truthAt(stamp);
        have_truth = true;
      }
      const auto& se = sim_config_.entities[s->second];
      where = adk::scenarioEntityAt(se, stamp);
      for (const auto& e : truth) {
        if (e.id == box.entity_id) where = e;
      }
      pe.entity_class = scenario::toString(se.entity.cls);
      pe.role = se.role;
      pe.attributes = toKeyValues(se.entity.attributes);
    } else if (w != world_car_index_.end()) {
      where = world_cars_[w->second];
      const auto& we = world_->entities()[static_cast<std::size_t>(world_->find(box.entity_id))];
      pe.entity_class = "car";
      pe.role = "world";
      pe.attributes = toKeyValues(we.attributes);
    } else if (const scenario::Aircraft* a = aircraftById(box.entity_id)) {
      // Another aircraft of an avoid mission: its body centre on its scripted trajectory.
      const scenario::TrajectoryPoint q = scenario::sampleTrajectory(a->trajectory, stamp);
      where.position = geometry::Vec3(q.x, q.y, q.z);
      where.yaw = q.yaw;
      pe.entity_class = "aircraft";
      pe.role = "aircraft";
      scenario::Attributes model;
      model.set("model", a->model);
      pe.attributes = toKeyValues(model);
    } else if (box.role == "world" && box.entity_class != "car" &&
               box.entity_class != "pedestrian") {
      continue;  // the city's buildings and street furniture: scenery, not a perceived entity
    } else {
      HAMERITT_ERROR_THROTTLE(5.0,
                              "adk: camera %s: boxes[].entity_id '%s' is neither a scenario "
                              "entity nor a parked world car; ignored",
                              cam.name.c_str(), box.entity_id.c_str());
      continue;
    }
    pe.position.x = where.position.x();
    pe.position.y = where.position.y();
    pe.position.z = where.position.z();
    pe.yaw = where.yaw;
    metrics_->addSighting(box.entity_id, stamp, 1.0 / cam.rate_hz);
    report.entities.push_back(pe);
  }
  if (perfect_perception_) gate_->publish(perception_pub_, report);
  checkObjective(std::max(now_, stamp));
}

const scenario::Aircraft* AdkRos::aircraftById(const std::string& id) const {
  for (const auto& a : sim_config_.aircraft) {
    if (a.id == id) return &a;
  }
  return nullptr;
}

void AdkRos::onDetection(const hameritt::Detection::ConstPtr& msg) {
  if (finished_) return;
  const adk::DetectionClaim claim = fromMsg(*msg);
  adk::DetectionVerdict v;
  try {
    v = scorer_->score(claim, truthAt(claim.stamp));
  } catch (const adk::InputError& e) {
    HAMERITT_ERROR_THROTTLE(5.0, "adk: %s: detection from '%s': %s; ignored",
                            detection_sub_.getTopic().c_str(), msg->client.c_str(), e.what());
    return;
  }
  metrics_->addVerdict(claim.stamp, v);
  hameritt::DetectionScore s;
  s.header.stamp = msg->header.stamp;
  s.header.frame_id = "map";
  s.detection = *msg;
  s.verdict = adk::toString(v.verdict);
  s.matched_entity_id = v.entity_id;
  s.matched_role = v.role;
  s.position_error = v.position_error;
  s.first_correct = v.first_correct;
  gate_->publish(scores_pub_, s);
  checkObjective(std::max(now_, claim.stamp));
}

void AdkRos::finish() {
  if (finished_) return;
  finished_ = true;
  finished_at_ = ros::WallTime::now();
  std::string reason = lifecycle_->reason();
  if (watchdog_->lateStart() >= 0) {
    char late[160];
    std::snprintf(late, sizeof(late),
                  "; the ADK started at sim time %.3f s (restarted?): the metrics cover only the "
                  "mission from then on",
                  watchdog_->lateStart());
    reason += late;
  }
  adk::MissionMetrics m = metrics_->finish(adk::outcomeOf(lifecycle_->state()), reason,
                                           lifecycle_->startTime(), lifecycle_->endTime(),
                                           lifecycle_->timeLimit(), mode_, *monitor_, *coverage_);
  if (avoid_) {
    m.avoid = avoid_->score(monitor_->violationDuration());
    publishAvoid(lifecycle_->endTime(), *m.avoid);
  }
  if (follow_) {
    m.follow = followScore(true);
    publishFollow(lifecycle_->endTime(), *m.follow);
  }
  if (track_) {
    m.track = track_->score(true);
    publishTrack(lifecycle_->endTime(), *m.track);
  }
  // A phase still active when the mission ends has failed.
  for (const auto& phase : mission_.phases) {
    const auto it = phase_states_.find(phase.id);
    if (it != phase_states_.end() && it->second == adk::PhaseState::kActive) {
      const bool follow = follow_ && phase.id == follow_->phase().id;
      const bool track = track_ && phase.id == track_->phase().id;
      publishPhase(lifecycle_->endTime(), phase, adk::PhaseState::kFailed,
                   follow && !m.follow->failure.empty() ? m.follow->failure
                   : track && !m.track->failure.empty() ? m.track->failure
                                                        : reason);
    }
  }
  std::string file;
  if (!output_dir_.empty()) {
    try {
      std::error_code ec;
      std::filesystem::create_directories(output_dir_, ec);
      if (ec) {
        throw scenario::OutputError(output_dir_ + ": cannot create directory: " + ec.message());
      }
      file = output_dir_ + "/metrics.json";
      adk::writeMetricsJson(m, file);
    } catch (const std::exception& e) {
      ROS_ERROR("adk: metrics not written: %s", e.what());
      file.clear();
      write_failed_ = true;
    }
  }
  const ros::Time stamp = stampOf(lifecycle_->endTime());
  if (monitor_->sampleCount() > 0) publishConstraints(monitor_->lastTime());
  gate_->publish(metrics_pub_, toMsg(m, file, stamp));
  publishState();
  ROS_INFO(
      "adk: mission %s at t = %.3f s (%s); %zu keep-out violations, path %.1f m, "
      "energy %.0f J%s%s",
      adk::toString(m.outcome), m.end_time, m.reason.c_str(), m.violations.size(),
      m.flight.path_length, m.flight.energy, file.empty() ? "" : "; metrics in ", file.c_str());
}

int AdkRos::spin() {
  while (true) {
    gate_->spinOnce(0.02);
    if (!finished_) {
      const std::string stalled = watchdog_->stalled(ros::WallTime::now().toSec());
      if (!stalled.empty()) {
        ROS_ERROR("adk: %s: aborting the mission", stalled.c_str());
        lifecycle_->abort(now_, stalled);
        finish();
      }
    }
    if (sim_end_pending_ && (ros::WallTime::now() - sim_end_seen_).toSec() >= 1.0) {
      endAtSimulationEnd(true);
    }
    if (g_stop || !ros::ok()) {
      if (!finished_) {
        std::string why =
            g_stop ? "interrupted (SIGINT/SIGTERM) before the end" : "ROS shut down before the end";
        // The launch ends when its required recorder stops, which it does for lack of space.
        const std::string disk = recorderDiskShortage();
        if (!disk.empty()) why = disk + "; " + why;
        lifecycle_->abort(now_, why);
        finish();
      }
      break;
    }
    if (finished_ && shutdown_on_end_ &&
        (ros::WallTime::now() - finished_at_).toSec() >= end_linger_) {
      break;
    }
  }
  gate_->leave();
  ros::shutdown();
  return write_failed_ ? 1 : 0;
}

}  // namespace hameritt::ros_wrappers
