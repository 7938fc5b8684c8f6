#include "hameritt/ros/simulator_ros.h"

#include <ros/callback_queue.h>
#include <ros/master.h>
#include <rosgraph_msgs/Clock.h>
#include <std_msgs/String.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "hameritt/CrashEvent.h"
#include "hameritt/EntityStateArray.h"
#include "hameritt/SimulationEnd.h"
#include "hameritt/ros/conversions.h"
#include "hameritt/ros/log_throttle.h"
#include "hameritt/scenario/error.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/sim/quadrotor.h"

namespace hameritt::ros_wrappers {

namespace {

int ratio(double physics_hz, double rate_hz, const char* name) {
  if (!(rate_hz > 0 && rate_hz <= physics_hz)) {
    throw scenario::ConfigError(std::string("~") + name + ": expected a rate in (0, physics_rate_hz], got " +
                                std::to_string(rate_hz));
  }
  const double steps = physics_hz / rate_hz;
  if (std::abs(steps - std::round(steps)) > 1e-9) {
    throw scenario::ConfigError(std::string("~") + name + ": expected a rate that divides physics_rate_hz (" +
                                std::to_string(physics_hz) + ") into whole steps, got " +
                                std::to_string(rate_hz));
  }
  return static_cast<int>(std::round(steps));
}

// Comma-separated names, each trimmed and resolved; empty ones dropped.
std::vector<std::string> resolvedList(const std::string& list) {
  std::vector<std::string> out;
  for (std::size_t a = 0; a < list.size();) {
    std::size_t b = list.find(',', a);
    if (b == std::string::npos) b = list.size();
    std::string t = list.substr(a, b - a);
    t.erase(0, t.find_first_not_of(' '));
    t.erase(t.find_last_not_of(' ') + 1);
    if (!t.empty()) out.push_back(ros::names::resolve(t));
    a = b + 1;
  }
  return out;
}

// The map frame's geodetic origin (~origin_latitude/longitude/altitude; the defaults are the
// shipped scenarios' origin).
cop::Geodetic loadOrigin(ros::NodeHandle& pnh) {
  cop::Geodetic o;
  pnh.param("origin_latitude", o.latitude, 42.4851);
  pnh.param("origin_longitude", o.longitude, -71.1873);
  pnh.param("origin_altitude", o.altitude, 40.0);
  return o;
}

}  // namespace

SimulatorRos::SimulatorRos(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  std::string sim_config, urdf;
  if (!pnh.getParam("sim_config", sim_config)) {
    throw scenario::ConfigError("~sim_config: required parameter (path of a sim_config.json)");
  }
  pnh.param<std::string>("urdf", urdf, sim::defaultQuadrotorUrdf());
  sim::SimSettings settings;
  pnh.param("physics_rate_hz", settings.physics_rate_hz, settings.physics_rate_hz);
  pnh.param("real_time_factor", real_time_factor_, 0.0);
  pnh.param("start_paused", paused_, false);
  pnh.param("duration", duration_, 0.0);
  double publish_hz = 250.0, truth_hz = 20.0;
  pnh.param("publish_rate_hz", publish_hz, publish_hz);
  pnh.param("ground_truth_rate_hz", truth_hz, truth_hz);
  settings.validate();
  if (!(real_time_factor_ >= 0)) {
    throw scenario::ConfigError("~real_time_factor: expected >= 0 (0 = unpaced), got " +
                                std::to_string(real_time_factor_));
  }
  std::string wait_for;
  pnh.param<std::string>("wait_for", wait_for, "");
  pnh.param("wait_timeout", wait_timeout_, wait_timeout_);
  wait_for_ = resolvedList(wait_for);
  std::string wait_for_nodes;
  pnh.param<std::string>("wait_for_nodes", wait_for_nodes, "");
  wait_for_nodes_ = resolvedList(wait_for_nodes);
  steps_per_publish_ = ratio(settings.physics_rate_hz, publish_hz, "publish_rate_hz");
  steps_per_ground_truth_ = ratio(settings.physics_rate_hz, truth_hz, "ground_truth_rate_hz");
  gate_ = std::make_unique<LockstepGate>(nh, pnh, LockstepGate::Role::kCoordinator);
  if (gate_->enabled()) {
    std::string participants;
    pnh.param<std::string>("lockstep_participants", participants, "");
    lockstep_participants_ = resolvedList(participants);
    double period = 0.02;
    pnh.param("lockstep_period", period, period);
    const double steps = period * settings.physics_rate_hz;
    if (!(steps >= 1 && std::abs(steps - std::round(steps)) < 1e-6 &&
          static_cast<long>(std::round(steps)) % steps_per_publish_ == 0)) {
      throw scenario::ConfigError(
          "~lockstep_period: expected a multiple of the publish period (" +
          std::to_string(steps_per_publish_ / settings.physics_rate_hz) + " s), got " +
          std::to_string(period));
    }
    steps_per_cycle_ = static_cast<int>(std::round(steps));
  }

  pnh.param<std::string>("autopilot", autopilot_, autopilot_);
  if (autopilot_ != "internal" && autopilot_ != "px4" && autopilot_ != "ardupilot") {
    throw scenario::ConfigError("~autopilot: expected internal, px4 or ardupilot, got '" +
                                autopilot_ + "'");
  }
  if (autopilot_ != "internal" && gate_->enabled()) {
    throw scenario::ConfigError(
        "~autopilot " + autopilot_ +
        " with /lockstep true: not supported (the autopilot's own "
        "lock-step paces the simulation by its actuator messages, the mission's lock-step by the "
        "nodes' turns; run one of them: lockstep:=false with an autopilot)");
  }

  config_ = scenario::loadSimConfig(sim_config);
  if (duration_ <= 0) duration_ = config_.duration;
  world_ = std::make_unique<scenario::World>(scenario::generateCheckedWorld(config_, sim_config));
  sim_ = std::make_unique<sim::Simulator>(*world_, config_, sim::loadQuadrotorUrdf(urdf), settings);
  double fence_margin = 50.0;
  pnh.param("geofence_margin", fence_margin, fence_margin);
  if (!(fence_margin >= 0 && fence_margin <= 10000)) {
    throw scenario::ConfigError("~geofence_margin: expected metres in [0, 10000], got " +
                                std::to_string(fence_margin));
  }
  sim::Geofence fence;
  const geometry::Aabb2 b = world_->bounds();
  fence.min = sim::Vec3(b.min.x() - fence_margin, b.min.y() - fence_margin, 0.0);
  fence.max = sim::Vec3(b.max.x() + fence_margin, b.max.y() + fence_margin,
                        config_.uav.altitude_max + fence_margin);
  fence.brake_distance = std::min(20.0, fence_margin);
  guard_ = std::make_unique<sim::SetpointGuard>(fence, sim_->params());
  if (autopilot_ != "internal") {
    loadAutopilot(pnh, settings.physics_rate_hz);
  } else {
    // Ground-station telemetry while the built-in controller flies (off: none).
    std::string gcs;
    pnh.param<std::string>("gcs_udp", gcs, "127.0.0.1:14550");
    if (gcs != "off") {
      sitl::GcsConfig gc;
      const std::size_t colon = gcs.rfind(':');
      gc.address = gcs.substr(0, colon);
      gc.port = colon == std::string::npos ? 0 : std::atoi(gcs.c_str() + colon + 1);
      pnh.param("gcs_rate_hz", gc.rate_hz, gc.rate_hz);
      gc.origin = loadOrigin(pnh);
      gcs_ = std::make_unique<sitl::GcsTelemetry>(gc);
      ROS_INFO("simulator: MAVLink telemetry for ground stations to UDP %s", gcs.c_str());
    }
  }
  bool cameras = true;
  pnh.param("cameras", cameras, true);
  if (cameras && !config_.uav.cameras.empty()) {
    CameraRigOptions co;
    co.physics_rate_hz = settings.physics_rate_hz;
    pnh.param<std::string>("render_backend", co.backend, co.backend);
    pnh.param("camera_weather", co.weather, co.weather);
    pnh.param("camera_noise", co.noise, co.noise);
    pnh.param("render_queue_depth", co.queue_depth, co.queue_depth);
    pnh.param("render_lod_px", co.lod_max_error_px, co.lod_max_error_px);
    pnh.param("render_threads", co.render_threads, co.render_threads);
    if (!std::isfinite(co.lod_max_error_px) || co.lod_max_error_px < 0) {
      throw scenario::ConfigError("~render_lod_px: expected a number >= 0 (0: full detail), got " +
                                  std::to_string(co.lod_max_error_px));
    }
    pnh.param("record_image_rate", co.decimated_rate_hz, 0.0);
    std::string record_depth = "16UC1";
    pnh.param<std::string>("record_depth", record_depth, record_depth);
    if (record_depth != "16UC1" && record_depth != "32FC1") {
      throw scenario::ConfigError(
          "~record_depth: expected 16UC1 (millimetres) or 32FC1 (metres), got " + record_depth);
    }
    co.decimated_depth_mm = record_depth == "16UC1";
    bool record_rgb_noise = false;
    pnh.param("record_rgb_noise", record_rgb_noise, record_rgb_noise);
    co.decimated_rgb_noise_free = !record_rgb_noise;
    pnh.param("record_png_level", co.decimated_png_level, co.decimated_png_level);
    if (co.decimated_png_level > 9) {
      throw scenario::ConfigError(
          "~record_png_level: expected -1 (off) or a zlib level 0..9, got " +
          std::to_string(co.decimated_png_level));
    }
    if (co.queue_depth < 1) {
      throw scenario::ConfigError("~render_queue_depth: expected >= 1, got " + std::to_string(co.queue_depth));
    }
    co.gate = gate_.get();
    cameras_ = std::make_unique<CameraRig>(nh, *world_, config_, co);
    ROS_INFO("simulator: %zu cameras rendered with %s", config_.uav.cameras.size(),
             cameras_->glRenderer().c_str());
  }

  // A lock-step call publishes a burst of ticks at once: with a queue of 10, a recorder lost
  // about half of them at 25 ticks per call (test_mission_replay), differently in every run.
  clock_pub_ = gate_->advertise<rosgraph_msgs::Clock>(nh, "/clock", 1000);
  odom_pub_ = gate_->advertise<nav_msgs::Odometry>(nh, "uav/odom", 50);
  imu_pub_ = gate_->advertise<sensor_msgs::Imu>(nh, "uav/imu", 50);
  truth_pub_ = gate_->advertise<hameritt::EntityStateArray>(nh, "ground_truth/entities", 10);
  crash_pub_ = gate_->advertise<hameritt::CrashEvent>(nh, "uav/crash", 1, true);
  end_pub_ = gate_->advertise<hameritt::SimulationEnd>(pnh, "end", 1, true);
  if (gate_->enabled()) {
    // The tf broadcasters' topics (the same publications as theirs), for the connect phase.
    tf_watch_ = gate_->advertise<tf2_msgs::TFMessage>(nh, "/tf", 100);
    tf_static_watch_ = gate_->advertise<tf2_msgs::TFMessage>(nh, "/tf_static", 100, true);
  }
  vel_sub_ = gate_->subscribe(nh, "uav/cmd_vel", 10, &SimulatorRos::onVelocity, this);
  pose_sub_ = gate_->subscribe(nh, "uav/cmd_pose", 10, &SimulatorRos::onPose, this);
  step_srv_ = pnh.advertiseService("step", &SimulatorRos::onStep, this);
  pause_srv_ = pnh.advertiseService("set_paused", &SimulatorRos::onPause, this);
  reset_srv_ = pnh.advertiseService("reset", &SimulatorRos::onReset, this);
  publishStaticFrames();
  // In lock-step nothing is published before the connect phase but latched messages (a
  // subscriber that connects later gets exactly the one message counted).
  if (!gate_->enabled()) publishState(true);
  ROS_INFO("simulator: %s, %zu world entities, %zu scenario entities, %.0f Hz physics, %s",
           config_.scenario_id.c_str(), world_->entities().size(), config_.entities.size(),
           settings.physics_rate_hz, paused_ ? "paused" : "running");
}

void SimulatorRos::loadAutopilot(ros::NodeHandle& pnh, double physics_rate_hz) {
  sitl::Px4Config pc;
  pnh.param("px4_port", pc.port, pc.port);
  pnh.param("instance", pc.instance, pc.instance);
  pnh.param<std::string>("sitl_bind_address", pc.bind_address, pc.bind_address);
  pnh.param("sitl_sensor_rate_hz", pc.sensor_rate_hz, pc.sensor_rate_hz);
  pnh.param("sitl_gps_rate_hz", pc.gps_rate_hz, pc.gps_rate_hz);
  pnh.param("sitl_timeout", pc.stall_timeout_s, pc.stall_timeout_s);
  pnh.param("sitl_silent_timeout", pc.silent_timeout_s, pc.silent_timeout_s);
  pnh.param("sitl_max_rotor_speed", pc.max_rotor_speed, pc.max_rotor_speed);
  std::string layout;
  pnh.param<std::string>("rotor_layout", layout, "");
  pc.layout = layout.empty() ? sim::quadXLayout(sim_->params())
                             : sim::parseRotorLayout(layout, "~rotor_layout");
  sitl::SensorConfig sc;
  sc.origin = loadOrigin(pnh);
  int seed = static_cast<int>(config_.seed & 0x7FFFFFFF);
  pnh.param("sitl_seed", seed, seed);
  sc.seed = static_cast<std::uint64_t>(seed);
  auto& n = sc.noise;
  pnh.param("sitl_accel_noise", n.accel_noise, n.accel_noise);
  pnh.param("sitl_gyro_noise", n.gyro_noise, n.gyro_noise);
  pnh.param("sitl_mag_noise", n.mag_noise, n.mag_noise);
  pnh.param("sitl_baro_noise", n.baro_noise, n.baro_noise);
  pnh.param("sitl_gps_horizontal", n.gps_horizontal, n.gps_horizontal);
  pnh.param("sitl_gps_vertical", n.gps_vertical, n.gps_vertical);
  pnh.param("sitl_gps_velocity", n.gps_velocity, n.gps_velocity);
  std::vector<double> bias;
  if (pnh.getParam("sitl_accel_bias", bias)) {
    if (bias.size() != 3)
      throw scenario::ConfigError("~sitl_accel_bias: expected 3 numbers (FRD m/s^2)");
    n.accel_bias = sim::Vec3(bias[0], bias[1], bias[2]);
  }
  if (pnh.getParam("sitl_gyro_bias", bias)) {
    if (bias.size() != 3)
      throw scenario::ConfigError("~sitl_gyro_bias: expected 3 numbers (FRD rad/s)");
    n.gyro_bias = sim::Vec3(bias[0], bias[1], bias[2]);
  }
  pnh.param("sitl_baro_bias", n.baro_bias, n.baro_bias);
  sc.validate();
  auto log = [](sitl::Px4Server::LogLevel level, const std::string& m) {
    if (level == sitl::Px4Server::LogLevel::kError)
      ROS_ERROR("simulator: %s", m.c_str());
    else if (level == sitl::Px4Server::LogLevel::kWarn)
      ROS_WARN("simulator: %s", m.c_str());
    else
      ROS_INFO("simulator: %s", m.c_str());
  };
  if (autopilot_ == "px4") {
    px4_ = std::make_unique<sitl::Px4Server>(pc, sc, sim_->params(), physics_rate_hz, log);
  } else {
    sitl::ArduPilotConfig ac;
    pnh.param("ardupilot_port", ac.port, ac.port);
    ac.instance = pc.instance;
    ac.bind_address = pc.bind_address;
    ac.sensor_rate_hz = pc.sensor_rate_hz;
    ac.stall_timeout_s = pc.stall_timeout_s;
    ac.layout = pc.layout;
    ac.max_rotor_speed = pc.max_rotor_speed;
    ardupilot_ = std::make_unique<sitl::ArduPilotServer>(
        ac, sc, sim_->params(), physics_rate_hz,
        [log](sitl::ArduPilotServer::LogLevel level, const std::string& m) {
          log(static_cast<sitl::Px4Server::LogLevel>(level), m);
        });
  }
  autopilot_counters_pub_ = pnh.advertise<std_msgs::String>("autopilot_counters", 1, true);
}

bool SimulatorRos::exchangeWithAutopilot() {
  const ros::WallTime now = ros::WallTime::now();
  if ((now - counters_published_).toSec() >= 0.5) {
    counters_published_ = now;
    std_msgs::String m;
    m.data = px4_ ? sitl::toJson(px4_->counters()) : sitl::toJson(ardupilot_->counters());
    autopilot_counters_pub_.publish(m);
  }
  if (ardupilot_) {
    ardupilot_->service(0.0);
    if (!ardupilot_->readyToStep()) {
      ardupilot_->service(0.002);
      if (!ardupilot_->readyToStep()) return false;
    }
    ardupilot_->applyMotors(*sim_);
    advance(ardupilot_->stepsPerExchange());
    ardupilot_->sendState(sim_->uav());
    return true;
  }
  px4_->service(0.0);
  if (!px4_->readyToStep()) {
    // Lock-step: sim time stands still until the autopilot answers (or the stall timeout).
    px4_->service(0.002);
    if (!px4_->readyToStep()) return false;
  }
  px4_->applyMotors(*sim_);
  advance(px4_->stepsPerExchange());
  px4_->sendSensors(sim_->uav());
  return true;
}

void SimulatorRos::publishStaticFrames() {
  std::vector<geometry_msgs::TransformStamped> frames;
  for (const auto& c : config_.uav.cameras) frames.push_back(toCameraTransform(c, ros::Time(0)));
  if (cameras_) {
    for (const auto& [frame, mount] : cameras_->opticalMounts()) {
      frames.push_back(toTransformMsg(mount, kBaseFrame, frame, ros::Time(0)));
    }
  }
  static_tf_.sendTransform(frames);
  gate_->count("/tf_static");
}

void SimulatorRos::publishGroundTruth() {
  ros::Time stamp;
  stamp.fromSec(sim_->uav().t);
  hameritt::EntityStateArray truth;
  truth.header.stamp = stamp;
  truth.header.frame_id = kMapFrame;
  std::vector<geometry_msgs::TransformStamped> tfs;
  for (const auto& e : sim_->scenarioEntities()) {
    truth.entities.push_back(toMsg(e, stamp));
    if (e.role != "static") tfs.push_back(toEntityTransform(e, stamp));
  }
  gate_->publish(truth_pub_, truth);
  if (!tfs.empty()) {
    tf_.sendTransform(tfs);
    gate_->count("/tf");
  }
}

void SimulatorRos::publishState(bool force_ground_truth) {
  const sim::UavState& s = sim_->uav();
  ros::Time stamp;
  stamp.fromSec(s.t);
  rosgraph_msgs::Clock clock;
  clock.clock = stamp;
  gate_->publish(clock_pub_, clock);
  gate_->publish(odom_pub_, toOdometryMsg(s, stamp));
  gate_->publish(imu_pub_, toImuMsg(s, stamp));
  if (gcs_) gcs_->update(s, s.rotor_speeds.maxCoeff() > 0);
  tf_.sendTransform(toBaseTransform(s, stamp));
  gate_->count("/tf");
  if (force_ground_truth) publishGroundTruth();
  if (s.crashed && !crash_reported_) {
    crash_reported_ = true;
    hameritt::CrashEvent ev;
    ev.header.stamp = stamp;
    ev.header.frame_id = kMapFrame;
    ev.entity_id = s.crashed_into;
    ev.position.x = s.position.x();
    ev.position.y = s.position.y();
    ev.position.z = s.position.z();
    ev.speed = s.velocity.norm();
    gate_->publish(crash_pub_, ev);
    ROS_WARN("simulator: UAV crashed into %s at t=%.3f s", s.crashed_into.c_str(), s.crash_time);
  }
}

void SimulatorRos::advance(int steps) {
  for (int i = 0; i < steps; ++i) {
    sim_->step();
    ++step_count_;
    if (cameras_) cameras_->afterStep(step_count_, sim_->uav());
    if (step_count_ % steps_per_publish_ == 0) {
      publishState(false);
      applyVelocity();
    }
    // Ground truth on its own schedule (its rate need not be a multiple of the publish rate).
    if (step_count_ % steps_per_ground_truth_ == 0) publishGroundTruth();
  }
}

int SimulatorRos::subscribers(const std::string& topic) const {
  for (const ros::Publisher* p : {&clock_pub_, &odom_pub_, &imu_pub_, &truth_pub_, &crash_pub_}) {
    if (p->getTopic() == topic) return static_cast<int>(p->getNumSubscribers());
  }
  return cameras_ ? cameras_->subscribers(topic) : -1;
}

void SimulatorRos::waitForSubscribers() {
  if (wait_for_.empty() && wait_for_nodes_.empty()) return;
  for (const auto& t : wait_for_) {
    if (subscribers(t) < 0) ROS_WARN("simulator: ~wait_for: %s is not a topic of this node; ignored", t.c_str());
  }
  // Nodes that wait for a valid (non-zero) sim time before subscribing, such as rosbag record,
  // would otherwise wait for us while we wait for them: announce t = 1 ns (the first step is
  // still at t = dt, so the clock stays monotonic).
  rosgraph_msgs::Clock tick;
  tick.clock = ros::Time(0, 1);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(wait_timeout_);
  while (ros::ok()) {
    clock_pub_.publish(tick);
    std::string missing;
    for (const auto& t : wait_for_) {
      if (subscribers(t) == 0) missing += (missing.empty() ? "" : ", ") + t;
    }
    if (!wait_for_nodes_.empty()) {
      // Client nodes (the baselines or a user's own): known to the master once they have
      // initialised ROS.
      std::vector<std::string> nodes;
      ros::master::getNodes(nodes);
      for (const auto& n : wait_for_nodes_) {
        if (std::find(nodes.begin(), nodes.end(), n) == nodes.end()) {
          missing += (missing.empty() ? "" : ", ") + n;
        }
      }
    }
    if (missing.empty()) return;
    if (ros::WallTime::now() > deadline) {
      ROS_WARN("simulator: starting without %s (~wait_timeout %.0f s)", missing.c_str(),
               wait_timeout_);
      return;
    }
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.05));
  }
}

void SimulatorRos::spin() {
  waitForSubscribers();
  // Lock-step: each step of the loop is a cycle with the participants' turns after it.
  const bool lockstep = gate_->enabled();
  if (lockstep && !gate_->start(lockstep_participants_)) return;
  ros::WallTime wall_start = ros::WallTime::now();
  double sim_start = sim_->time();
  // Progress: sim time against wall time since the clock started (the real-time factor).
  const ros::WallTime run_start = wall_start;
  double next_report = 10.0;
  std::uint64_t cycle = 0;
  auto report = [&] {
    const double wall = (ros::WallTime::now() - run_start).toSec();
    if (lockstep) {
      ROS_INFO("simulator: lock-step cycle %llu: sim %.1f s in wall %.1f s (%.2fx real time), "
               "%zu participants",
               static_cast<unsigned long long>(cycle), sim_->time(), wall,
               sim_->time() / std::max(wall, 1e-9), gate_->participants().size());
    } else {
      ROS_INFO("simulator: sim %.1f s in wall %.1f s (%.2fx real time), %llu camera frames",
               sim_->time(), wall, sim_->time() / std::max(wall, 1e-9),
               static_cast<unsigned long long>(cameras_ ? cameras_->framesPublished() : 0));
    }
  };
  bool was_paused = paused_;
  bool ended = false;
  while (ros::ok()) {
    const bool running = !paused_ && sim_->time() < duration_;
    if (!running) {
      if (!lockstep && sim_->time() >= duration_) publishEndOnce();
      if (lockstep && !ended && sim_->time() >= duration_) {
        ended = true;
        ROS_INFO("simulator: lock-step: stopped at the duration, sim %.3f s, cycle %llu, in wall "
                 "%.1f s; %zu participants left",
                 sim_->time(), static_cast<unsigned long long>(cycle),
                 (ros::WallTime::now() - run_start).toSec(), gate_->participants().size());
      }
      ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.01));
      was_paused = true;
      continue;
    }
    if (was_paused) {
      // Pacing restarts from where the pause left off.
      sim_start = sim_->time();
      wall_start = ros::WallTime::now();
      was_paused = false;
    }
    if (lockstep) {
      gate_->beforeCycle();
      advance(steps_per_cycle_);
      if (cameras_) cameras_->flush();
      // In the last cycle's messages, so that the participants' last turn hands it over.
      if (sim_->time() >= duration_) publishEndOnce();
      ros::Time stamp;
      stamp.fromSec(sim_->time());
      if (!gate_->afterCycle(++cycle, stamp)) break;
    } else if (px4_ || ardupilot_) {
      if (!exchangeWithAutopilot()) {
        ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0));
        continue;
      }
    } else {
      advance(steps_per_publish_);
    }
    if (sim_->time() >= next_report) {
      report();
      next_report += 10.0;
    }
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0));
    if (real_time_factor_ > 0) {
      const double due = (sim_->time() - sim_start) / real_time_factor_;
      const double ahead = due - (ros::WallTime::now() - wall_start).toSec();
      if (ahead > 0) ros::WallDuration(ahead).sleep();
    }
  }
}

void SimulatorRos::publishEndOnce() {
  if (end_published_) return;
  end_published_ = true;
  hameritt::SimulationEnd m;
  m.header.stamp.fromSec(sim_->time());
  m.duration = duration_;
  char reason[96];
  std::snprintf(reason, sizeof(reason), "simulation duration %g s reached", duration_);
  m.reason = reason;
  gate_->publish(end_pub_, m);
  ROS_INFO("simulator: %s at sim %.3f s (~end)", m.reason.c_str(), sim_->time());
}

void SimulatorRos::applyVelocity() {
  if (!velocity_mode_) return;
  sim_->setVelocitySetpoint(guard_->fenceVelocity(sim_->uav().position, cmd_velocity_),
                            cmd_yaw_rate_);
}

void SimulatorRos::onVelocity(const geometry_msgs::Twist::ConstPtr& msg) {
  if (px4_ || ardupilot_) {
    HAMERITT_INFO_THROTTLE(30.0, "simulator: %s ignored: the %s autopilot flies the UAV",
                           vel_sub_.getTopic().c_str(), autopilot_.c_str());
    return;
  }
  sim::Vec3 v(msg->linear.x, msg->linear.y, msg->linear.z);
  double yaw_rate = msg->angular.z;
  const sim::SetpointCheck c = guard_->checkVelocity(&v, &yaw_rate);
  if (!c.error.empty()) {
    HAMERITT_ERROR_THROTTLE(5.0, "simulator: %s: %s; setpoint ignored", vel_sub_.getTopic().c_str(),
                            c.error.c_str());
    return;
  }
  if (!c.clamped.empty()) {
    HAMERITT_ERROR_THROTTLE(5.0, "simulator: %s: clamped %s", vel_sub_.getTopic().c_str(),
                            c.clamped.c_str());
  }
  cmd_velocity_ = v;
  cmd_yaw_rate_ = yaw_rate;
  velocity_mode_ = true;
  applyVelocity();
}

void SimulatorRos::onPose(const geometry_msgs::PoseStamped::ConstPtr& msg) {
  if (px4_ || ardupilot_) {
    HAMERITT_INFO_THROTTLE(30.0, "simulator: %s ignored: the %s autopilot flies the UAV",
                           pose_sub_.getTopic().c_str(), autopilot_.c_str());
    return;
  }
  if (!msg->header.frame_id.empty() && msg->header.frame_id != kMapFrame) {
    HAMERITT_ERROR_THROTTLE(
        5.0, "simulator: %s: header.frame_id: expected '%s' (or empty), got '%s'; setpoint ignored",
        pose_sub_.getTopic().c_str(), kMapFrame, msg->header.frame_id.c_str());
    return;
  }
  const auto& q = msg->pose.orientation;
  double roll, pitch, yaw;
  tf2::Matrix3x3(tf2::Quaternion(q.x, q.y, q.z, q.w)).getRPY(roll, pitch, yaw);
  sim::Vec3 p(msg->pose.position.x, msg->pose.position.y, msg->pose.position.z);
  const sim::SetpointCheck c = guard_->checkPosition(&p, &yaw);
  if (!c.error.empty()) {
    HAMERITT_ERROR_THROTTLE(5.0, "simulator: %s: %s; setpoint ignored",
                            pose_sub_.getTopic().c_str(), c.error.c_str());
    return;
  }
  if (!c.clamped.empty()) {
    HAMERITT_ERROR_THROTTLE(5.0, "simulator: %s: clamped %s", pose_sub_.getTopic().c_str(),
                            c.clamped.c_str());
  }
  velocity_mode_ = false;
  sim_->setPositionSetpoint(p, yaw);
}

bool SimulatorRos::onStep(hameritt::StepSimulation::Request& req,
                          hameritt::StepSimulation::Response& res) {
  if (!paused_) {
    res.success = false;
    res.code = 2;
    res.message = "pause the simulator (~set_paused) before stepping it";
  } else if (req.steps > 1000000) {
    res.success = false;
    res.code = 2;
    res.message = "steps: at most 1000000 per call";
  } else {
    advance(static_cast<int>(req.steps));
    if (cameras_) cameras_->flush();
    publishState(true);
    res.success = true;
    res.code = 0;
    res.message = "stepped " + std::to_string(req.steps);
  }
  res.sim_time = sim_->time();
  return true;
}

bool SimulatorRos::onPause(hameritt::SetPaused::Request& req, hameritt::SetPaused::Response& res) {
  paused_ = req.paused;
  res.success = true;
  res.code = 0;
  res.message = paused_ ? "paused" : "running";
  res.sim_time = sim_->time();
  return true;
}

bool SimulatorRos::onReset(hameritt::ResetSimulation::Request&,
                           hameritt::ResetSimulation::Response& res) {
  if (cameras_) cameras_->flush();
  sim_->reset();
  velocity_mode_ = false;
  step_count_ = 0;
  crash_reported_ = false;
  end_published_ = false;
  publishState(true);
  res.success = true;
  res.code = 0;
  res.message = "reset to t = 0";
  return true;
}

}  // namespace hameritt::ros_wrappers
