#include "hameritt/ros/coverage_search_client_ros.h"

#include <nav_msgs/Path.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "hameritt/clients/public_config.h"
#include "hameritt/ros/adk_conversions.h"
#include "hameritt/ros/client_conversions.h"
#include "hameritt/ros/mission_conversions.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/sim_config_io.h"

namespace hameritt::ros_wrappers {

namespace {

constexpr const char* kClientName = "coverage_search_client";

geometry_msgs::PoseStamped poseAt(const geometry::Vec3& p, const ros::Time& stamp) {
  geometry_msgs::PoseStamped m;
  m.header.stamp = stamp;
  m.header.frame_id = "map";
  m.pose.position.x = p.x();
  m.pose.position.y = p.y();
  m.pose.position.z = p.z();
  m.pose.orientation.w = 1.0;
  return m;
}

// A pose that faces `yaw`.
geometry_msgs::PoseStamped poseAt(const geometry::Vec3& p, double yaw, const ros::Time& stamp) {
  geometry_msgs::PoseStamped m = poseAt(p, stamp);
  m.pose.orientation.z = std::sin(0.5 * yaw);
  m.pose.orientation.w = std::cos(0.5 * yaw);
  return m;
}

// Seconds without a sighting after which the pursued vehicle counts as lost.
constexpr double kLostAfter = 2.0;
// A sighting of the description farther from the prediction than the gate is another vehicle
// (a parked look-alike the target drives past): 2.5 m while the track is fresh, growing by 2 m
// per second without a sighting (the prediction's error grows), at most 25 m.
double associationGate(double unseen) { return std::min(25.0, 2.5 + 2.0 * std::max(0.0, unseen)); }
// Unseen for longer than this, a sighting is matched against every branch of the prediction
// (the vehicle may have turned while hidden), not only the straight-on one.
constexpr double kBranchAfter = 0.5;
// A sighting this close to a parked car of the public map is that car.
constexpr double kParkedRadius = 1.5;
// Several targets held in one image: metres to spare beyond the outermost ones.
constexpr double kGroupMargin = 4.0;
// Per pursuit tick (10 Hz by default): the tilt shift's running average, about 4 s.
constexpr double kTiltAveraging = 0.025;
// The tilt is averaged only while the UAV is within this many metres of its station (its shifted
// viewpoint less the lag behind it) and its velocity within this many m/s of the vehicle's
// (clients::TiltAverage).
constexpr double kTiltStation = 8.0;
constexpr double kTiltSteady = 1.5;
// A sighting this close to the pursued vehicle's prediction is that vehicle.
constexpr double kSameVehicle = 6.0;
// A prediction this fast (m/s) is of a vehicle driving: a look-alike standing still is not it.
constexpr double kDriving = 2.0;
// A track phase's targets drive together ("the ... behind it"): while the pursuit holds one, a
// look-alike of another target's description farther than this (m) from it is another vehicle.
constexpr double kConvoyRadius = 80.0;
// And one of a target's description is claimed only beside a sighting of another target's
// description (within kConvoyRadius) of the last this many seconds.
constexpr double kConvoyWindow = 20.0;
// Before a convoy sets off, its cars wait together (the second one in the lane 22 m behind the
// first one's kerb slot): a standing car of another target's description this near (m) the
// held vehicle, itself standing, is its partner, not a parked look-alike.
constexpr double kConvoyWait = 30.0;
// A pursuit lost before the find is confirmed (no target state from the ADK and, on a track
// phase, no target claimed), with the UAV within kLeadReach (m, horizontally) of the prediction
// for kAbandonAfter s, was a false lead: the search goes on, and a sighting within
// kFalseLeadRadius (m) of where it was last seen starts no pursuit and no claim again (else the
// client hovered at the prediction of a look-alike seen once, standing, or of a car glimpsed
// from afar that drove off: a pursuit mission's search claimed a look-alike no relation could
// check, lost it 2 s later and hovered there for 220 s). (Lost on the way, a glimpse 150-250 m
// off is reacquired on arrival: 16-22 s lost in 11 of 46 successful track missions.)
constexpr double kLeadReach = 20.0;
constexpr double kAbandonAfter = 10.0;
constexpr double kFalseLeadRadius = 8.0;
// maneuver_only: the ADK sends a found target's state from the find on (10 Hz of sim time). A
// pursuit class's pursuit starts with its claim: no state this long (s) after it, the claim was of
// a look-alike (the second look-alike of the mission above, standing, was held in view to the
// end) and the pursuit is given up as a false lead at once.
constexpr double kConfirmWait = 3.0;
// The pursuit flies straight at its viewpoint only this far (beyond the 1 m margin) from every
// obstacle, else through the planner.
constexpr double kStraightClearance = 2.0;
// A claim's sighting lies within this many times a level camera's reach of the UAV (a little
// tilt is the flight's own).
constexpr double kLevelMargin = 1.25;
// Detection claims come seconds apart: their gate.
constexpr double kAssociationGate = 15.0;

}  // namespace

CoverageSearchClientRos::CoverageSearchClientRos(ros::NodeHandle& nh, ros::NodeHandle& pnh)
    : convoy_(kConvoyRadius, kConvoyWindow), tilt_(kTiltAveraging, kTiltStation, kTiltSteady) {
  gate_ = std::make_unique<LockstepGate>(nh, pnh);
  std::string sim_path, camera = "down";
  if (!pnh.getParam("sim_config", sim_path)) {
    throw scenario::ConfigError("~sim_config: required parameter (path of a sim_config.json)");
  }
  double altitude = 0.0, min_car_pixels = 25.0, overlap = 0.2, koz_margin = 3.0, rate = 2.0;
  double claim_radius = 4.0, claim_hold = 30.0;
  int max_leg = 12;
  bool cover_zero = false;
  pnh.param("camera", camera, camera);
  pnh.param("altitude", altitude, altitude);
  pnh.param("min_car_pixels", min_car_pixels, min_car_pixels);
  pnh.param("overlap", overlap, overlap);
  pnh.param("koz_margin", koz_margin, koz_margin);
  pnh.param("max_leg_waypoints", max_leg, max_leg);
  pnh.param("cover_zero_cells", cover_zero, cover_zero);
  pnh.param("repeat", repeat_, repeat_);
  pnh.param("stop_on_detection", stop_on_detection_, stop_on_detection_);
  pnh.param("claim_from_perfect_perception", claim_, claim_);
  pnh.param("use_context", use_context_, use_context_);
  pnh.param("claim_radius", claim_radius, claim_radius);
  pnh.param("claim_hold", claim_hold, claim_hold);
  pnh.param("mission_start_time", mission_start_, mission_start_);
  pnh.param("rate_hz", rate, rate);
  if (!(rate > 0 && rate <= 100)) throw scenario::ConfigError("~rate_hz: expected (0, 100]");
  double pursuit_rate = 10.0;
  pnh.param("pursue", pursue_, pursue_);
  pnh.param("publish_tracks", publish_tracks_, publish_tracks_);
  pnh.param("drive_off_speed", drive_off_speed_, drive_off_speed_);
  pnh.param("track_claim_camera", track_claim_camera_, track_claim_camera_);
  pnh.param("use_target_state", use_target_state_, use_target_state_);
  pnh.param("track_standoff", track_standoff_, track_standoff_);
  if (!(track_standoff_ >= 0 && std::isfinite(track_standoff_))) {
    throw scenario::ConfigError("~track_standoff: expected a finite number >= 0");
  }
  if (!(drive_off_speed_ >= 0)) throw scenario::ConfigError("~drive_off_speed: expected >= 0");
  std::string track_boxes = "perfect_perception";
  pnh.param("track_boxes", track_boxes, track_boxes);
  if (track_boxes != "perfect_perception" && track_boxes != "detector") {
    throw scenario::ConfigError("~track_boxes: expected perfect_perception or detector, got '" +
                                track_boxes + "'");
  }
  boxes_from_detector_ = track_boxes == "detector";
  pnh.param("pursuit_standoff", pursuit_.standoff, pursuit_.standoff);
  pnh.param("pursuit_height", pursuit_.height, pursuit_.height);
  pnh.param("pursuit_lead", pursuit_.lead, pursuit_.lead);
  pnh.param("pursuit_rate_hz", pursuit_rate, pursuit_rate);
  if (!(pursuit_rate > 0 && pursuit_rate <= 100)) {
    throw scenario::ConfigError("~pursuit_rate_hz: expected (0, 100]");
  }
  pursuit_.validate();
  double avoid_rate = 10.0;
  pnh.param("avoid", avoid_enabled_, avoid_enabled_);
  pnh.param("avoid_rate_hz", avoid_rate, avoid_rate);
  pnh.param("avoid_speed_fraction", avoid_settings_.speed_fraction, avoid_settings_.speed_fraction);
  pnh.param("avoid_horizontal_buffer", avoid_settings_.horizontal_buffer,
            avoid_settings_.horizontal_buffer);
  pnh.param("avoid_vertical_buffer", avoid_settings_.vertical_buffer,
            avoid_settings_.vertical_buffer);
  pnh.param("avoid_horizon", avoid_settings_.horizon, avoid_settings_.horizon);
  if (!(avoid_rate > 0 && avoid_rate <= 100)) {
    throw scenario::ConfigError("~avoid_rate_hz: expected (0, 100]");
  }
  avoid_settings_.validate();

  // The honesty rule: the map and the UAV's own specification, never the scenario's entities.
  sim_ = clients::loadPublicSimConfig(sim_path);
  settings_ = clients::coverageSettingsFor(sim_.uav, camera, altitude, min_car_pixels);
  settings_.overlap = overlap;
  settings_.koz_margin = koz_margin;
  settings_.max_leg_waypoints = max_leg;
  settings_.cover_zero_cells = cover_zero;
  settings_.validate();
  claims_ = clients::ClaimLedger(claim_radius, claim_hold);
  false_leads_ = clients::FalseLeads(kLeadReach, kAbandonAfter, kFalseLeadRadius);
  detections_ = clients::ClaimLedger(claim_radius, 0.0);
  world_ = std::make_unique<scenario::World>(scenario::generateCheckedWorld(sim_, sim_path));
  obstacles_ = std::make_unique<planning::WorldValidity>(
      *world_, std::vector<scenario::KeepOutZone>{}, planning::validitySettingsFor(sim_.uav));
  // The context filter reads the world only where the claims use the context.
  if ((claim_ && use_context_) || pursue_ || avoid_enabled_) context_world_ = world_.get();

  waypoints_pub_ = gate_->advertise<nav_msgs::Path>(nh, "planner/waypoints", 1, true);
  plan_pub_ = gate_->advertise<nav_msgs::Path>(pnh, "plan", 1, true);
  using Self = CoverageSearchClientRos;
  mission_sub_ = gate_->subscribe(nh, "mission", 1, &Self::onMission, this);
  odom_sub_ = gate_->subscribe(nh, "uav/odom", 10, &Self::onOdometry, this);
  progress_sub_ = gate_->subscribe(nh, "planner/progress", 50, &Self::onProgress, this);
  state_sub_ = gate_->subscribe(nh, "adk/state", 10, &Self::onState, this);
  detection_sub_ = gate_->subscribe(nh, "perception/detections", 50, &Self::onDetection, this);
  if (claim_) {
    detection_pub_ = gate_->advertise<hameritt::Detection>(nh, "perception/detections", 50);
    perfect_sub_ =
        gate_->subscribe(nh, "adk/perfect_perception", 20, &Self::onPerfectPerception, this);
    if (publish_tracks_) {
      tracks_pub_ = gate_->advertise<hameritt::TrackReport>(nh, "perception/tracks", 50);
      if (boxes_from_detector_) {
        blobs_sub_ = gate_->subscribe(nh, "perception/blobs", 20, &Self::onBlobs, this);
      }
    }
  }
  if (pursue_) {
    // The parked cars of the public map: a sighting at one's place is that car.
    for (const auto& e : world_->entities()) {
      if (e.cls == scenario::EntityClass::kCar) parked_.push_back(e.box.center2());
    }
    pose_pub_ = gate_->advertise<geometry_msgs::PoseStamped>(nh, "uav/cmd_pose", 10);
    predictor_ = std::make_unique<clients::StreetPredictor>(*world_, pursuit_);
    if (use_target_state_) {
      target_state_sub_ = gate_->subscribe(nh, "adk/target_state", 20, &Self::onTargetState, this);
    }
    gate_->every(nh, 1.0 / pursuit_rate, [this] { onPursuitTick(); });
  }
  if (avoid_enabled_) {
    if (!pose_pub_)
      pose_pub_ = gate_->advertise<geometry_msgs::PoseStamped>(nh, "uav/cmd_pose", 10);
    traffic_sub_ = gate_->subscribe(nh, "adk/traffic", 20, &Self::onTraffic, this);
    gate_->every(nh, 1.0 / avoid_rate, [this] { onAvoidTick(); });
  }
  gate_->every(nh, 1.0 / rate, [this] { onTick(); });
  ROS_INFO("%s: %s camera, altitude %.1f m, swath %.1f m, lines %.1f m apart%s", kClientName,
           camera.c_str(), settings_.altitude, settings_.footprint.across,
           settings_.footprint.across * (1 - settings_.overlap),
           claim_ ? ", claiming from perfect perception" : "");
}

double CoverageSearchClientRos::missionTime() const {
  return ros::Time::now().toSec() - mission_start_;
}

void CoverageSearchClientRos::onMission(const hameritt::Mission::ConstPtr& msg) {
  std::optional<scenario::Mission> m = acceptMission(*msg, sim_.scenario_id, kClientName);
  if (!m) return;
  if (mission_ && mission_->scenario_id == m->scenario_id) return;  // the same, again
  mission_ = std::move(*m);
  // A track mission's search goes on past its areas' windows (a false lead can take the time),
  // and what it finds then may have driven off from its area since (~drive_off_speed).
  clients::ContextSettings context;
  if (mission_->objective.type == "track") context.drive_off_speed = drive_off_speed_;
  filter_ = std::make_unique<clients::ContextFilter>(*mission_, context_world_, context);
  track_phase_ = std::any_of(mission_->phases.begin(), mission_->phases.end(),
                             [](const auto& p) { return p.type == scenario::PhaseType::kTrack; });
  // A follow phase states where to be: its envelope's d* behind and h* above the target.
  for (const auto& phase : mission_->phases) {
    if (phase.type != scenario::PhaseType::kFollow) continue;
    pursuit_.standoff = phase.follow.distance;  // >= 0 (mission.json)
    if (phase.follow.height > 0) pursuit_.height = phase.follow.height;
    pursuit_.envelope_radius = phase.follow.distance_tolerance;  // > 0 (mission.json)
    pursuit_.envelope_height = phase.follow.height_tolerance;
    ROS_INFO(
        "%s: follow phase '%s': standoff %.1f m behind, %.1f m above the target, within "
        "%.1f m and %.1f m",
        kClientName, phase.id.c_str(), pursuit_.standoff, pursuit_.height, pursuit_.envelope_radius,
        pursuit_.envelope_height);
  }
  // A track phase scores one camera's frames: viewpoints for it alone, above the vehicle.
  track_camera_.reset();
  if (track_phase_ && !track_claim_camera_.empty()) {
    for (const auto& c : sim_.uav.cameras) {
      // Several targets are held in its image from straight above: a nadir camera only.
      if (c.name == track_claim_camera_ && c.mount_rpy.y() > 80.0) track_camera_ = c;
    }
    pursuit_.camera = track_claim_camera_;
    pursuit_.standoff = track_standoff_;
    ROS_INFO("%s: track phase: viewpoints for the %s camera, %.1f m behind, %.1f m above",
             kClientName, pursuit_.camera.c_str(), pursuit_.standoff, pursuit_.height);
  }
  if (pursue_) {
    chooser_ =
        std::make_unique<clients::ViewpointChooser>(*world_, sim_.uav, mission_->kozs, pursuit_);
    predictor_ = std::make_unique<clients::StreetPredictor>(*world_, pursuit_);
  }
  covered_.clear();
  track_claimed_.clear();
  state_target_.clear();
  pursued_description_.clear();
  false_leads_.clear();
  convoy_.clear();
  other_targets_.clear();
  unclaimed_targets_.clear();
  reports_after_ = -1.0;
  planned_ = stopped_ = exhausted_ = pursuing_ = false;
  avoid_.reset();
  avoid_planned_ = avoid_arrived_ = false;
  ROS_INFO("%s: mission %s: %s", kClientName, mission_->scenario_id.c_str(),
           mission_->objective.text.c_str());
  const bool avoid_phase = std::any_of(
      mission_->phases.begin(), mission_->phases.end(),
      [](const scenario::MissionPhase& p) { return p.type == scenario::PhaseType::kAvoid; });
  if (avoid_enabled_ && avoid_phase) {
    try {
      avoid_ = std::make_unique<clients::AvoidPilot>(*world_, *mission_, sim_.uav, avoid_settings_);
    } catch (const std::exception& e) {
      ROS_ERROR("%s: avoid: %s", kClientName, e.what());
      stop("the avoid mission cannot be flown");
      return;
    }
    planned_ = true;  // no search: the pilot flies it
    return;
  }
  if (odom_) replan("mission received");
}

void CoverageSearchClientRos::onOdometry(const nav_msgs::Odometry::ConstPtr& msg) {
  odom_ = *msg;
  if (mission_ && !planned_ && !stopped_) replan("start");
}

void CoverageSearchClientRos::replan(const std::string& why) {
  const auto& p = odom_->pose.pose.position;
  clients::SearchProgress progress{geometry::Vec3(p.x, p.y, p.z), missionTime(), covered_};
  try {
    plan_ = clients::planSearch(*mission_, settings_, progress);
    // A target that drives off (pursuit, follow) leaves from its area of interest: when no cell
    // can be reached before the windows close, the areas are searched past their windows.
    const bool windows = std::any_of(mission_->aois.begin(), mission_->aois.end(),
                                     [](const auto& a) { return a.window.nlt.has_value(); });
    if (plan_.legs.empty() && !plan_.skipped.empty() && mission_->objective.type == "track" &&
        windows) {
      scenario::Mission open = *mission_;
      for (auto& a : open.aois) a.window.nlt.reset();
      plan_ = clients::planSearch(open, settings_, progress);
      ROS_INFO("%s: no cell can be reached inside the windows: searching the areas past them",
               kClientName);
    }
    const clients::WaypointRepairs fixed = clients::clearWaypoints(&plan_, *obstacles_);
    if (fixed.lifted + fixed.dropped > 0) {
      ROS_INFO("%s: %d sweep waypoints lifted over rooftops, %d dropped (above the band)",
               kClientName, fixed.lifted, fixed.dropped);
    }
  } catch (const std::exception& e) {
    ROS_ERROR("%s: planning the search failed: %s", kClientName, e.what());
    plan_ = {};
  }
  leg_ = 0;
  sent_ = acked_ = false;
  failures_ = 0;
  planned_ = true;
  std::size_t waypoints = 0;
  for (const auto& leg : plan_.legs) waypoints += leg.waypoints.size();
  ROS_INFO("%s: %s: %zu legs, %zu waypoints, %zu cells left out", kClientName, why.c_str(),
           plan_.legs.size(), waypoints, plan_.skipped.size());
  for (const auto& s : plan_.skipped) ROS_DEBUG("%s: left out %s", kClientName, s.c_str());
  publishPlan();
  sendIfDue();
}

void CoverageSearchClientRos::sendIfDue() {
  if (stopped_ || pursuing_ || !planned_ || sent_ || !mission_ || avoid_) return;
  if (leg_ >= plan_.legs.size()) {
    if (exhausted_) return;
    if (repeat_ && !covered_.empty()) {
      covered_.clear();
      replan("every open cell swept, sweeping again");
      return;
    }
    exhausted_ = true;
    ROS_INFO("%s: nothing left to search now: hovering", kClientName);
    if (odom_ && odom_->pose.pose.position.z > 1.0) {
      nav_msgs::Path path;
      path.header.stamp = ros::Time::now();
      path.header.frame_id = "map";
      const auto& p = odom_->pose.pose.position;
      path.poses.push_back(poseAt(geometry::Vec3(p.x, p.y, p.z), path.header.stamp));
      gate_->publish(waypoints_pub_, path);
    }
    return;
  }
  const clients::SearchLeg& leg = plan_.legs[leg_];
  const double t = missionTime();
  if (t < leg.not_before || t < retry_at_) return;
  nav_msgs::Path path;
  path.header.stamp = ros::Time::now();
  path.header.frame_id = "map";
  for (const auto& w : leg.waypoints) path.poses.push_back(poseAt(w.position, path.header.stamp));
  gate_->publish(waypoints_pub_, path);
  sent_ = true;
  acked_ = false;
  ROS_INFO("%s: leg %zu/%zu: %s %s (p %.3f), %zu waypoints", kClientName, leg_ + 1,
           plan_.legs.size(), leg.kind == clients::LegKind::kStage ? "waiting at" : "sweeping",
           leg.cell_id.c_str(), leg.probability, leg.waypoints.size());
}

void CoverageSearchClientRos::onProgress(const hameritt::FollowProgress::ConstPtr& msg) {
  if (!sent_ || stopped_ || pursuing_ || leg_ >= plan_.legs.size()) return;
  const clients::SearchLeg& leg = plan_.legs[leg_];
  if (!acked_) {
    // The follower's first answer to this leg: it plans as soon as the waypoints arrive.
    const bool answer = msg->state == "following" || msg->state == "failed";
    if (!answer || msg->waypoints != leg.waypoints.size()) return;
    acked_ = true;
  }
  if (msg->state == "failed") {
    legFailed(*msg);
  } else if (msg->state == "done") {
    sent_ = false;
    failures_ = 0;
    const bool cell_done = leg.kind == clients::LegKind::kCover && leg.completes_cell;
    const std::string cell = leg.cell_id;
    if (cell_done) covered_.insert(cell);
    ++leg_;
    if (cell_done) {
      replan(cell + " swept");
    } else {
      sendIfDue();
    }
  }
}

void CoverageSearchClientRos::legFailed(const hameritt::FollowProgress& msg) {
  clients::SearchLeg& leg = plan_.legs[leg_];
  ++failures_;
  sent_ = false;
  ROS_WARN("%s: the follower failed on leg %zu (%s) at waypoint %u: %s", kClientName, leg_ + 1,
           leg.cell_id.c_str(), msg.waypoint, msg.message.c_str());
  // Waypoints already reached are done; the failing one is retried once, then dropped.
  const std::size_t reached = std::min<std::size_t>(msg.waypoint, leg.waypoints.size());
  const std::size_t drop = failures_ >= 2 ? std::min(reached + 1, leg.waypoints.size()) : reached;
  leg.waypoints.erase(leg.waypoints.begin(), leg.waypoints.begin() + static_cast<long>(drop));
  if (failures_ >= 2) failures_ = 0;
  retry_at_ = missionTime() + 1.0;
  if (leg.waypoints.empty()) {
    if (leg.kind == clients::LegKind::kCover && leg.completes_cell) covered_.insert(leg.cell_id);
    ++leg_;
  }
  sendIfDue();
}

void CoverageSearchClientRos::onState(const topic_tools::ShapeShifter::ConstPtr& msg) {
  const auto reading = readMissionState(*msg);
  if (!reading) {
    ROS_WARN_ONCE("%s: adk/state (%s) has no state field this client can read", kClientName,
                  msg->getDataType().c_str());
    return;
  }
  if (reading->ended) stop("the ADK says the mission is over (" + reading->state + ")");
}

void CoverageSearchClientRos::onDetection(const hameritt::Detection::ConstPtr& msg) {
  if (!mission_ || !stop_on_detection_ || stopped_) return;
  clients::Observation seen;
  seen.entity_class = msg->entity_class;
  for (const auto& kv : msg->attributes) seen.attributes.emplace_back(kv.key, kv.value);
  bool wanted = false;
  for (const auto& t : mission_->objective.targets) wanted |= clients::matchesDescription(seen, t);
  if (!wanted) return;
  const geometry::Vec3 p(msg->position.x, msg->position.y, msg->position.z);
  const double t = msg->header.stamp.toSec() - mission_start_;
  // A pursuit fed by claims alone (no perfect perception): each claim near the prediction.
  if (pursue_ && !claim_ && predictor_ &&
      (!predictor_->tracking() ||
       (predictor_->predict(t).position - p).head<2>().norm() < kAssociationGate)) {
    predictor_->observe(t, p);
  }
  if (pursuing_) return;
  detections_.claim(p, msg->header.stamp.toSec());
  const std::size_t wanted_places = std::max<std::size_t>(1, mission_->objective.targets.size());
  if (detections_.locations() >= wanted_places) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "%s detected %s at (%.1f, %.1f)", msg->client.c_str(),
                  msg->description.c_str(), p.x(), p.y());
    if (pursue_ && mission_->objective.type == "track" && predictor_->tracking()) {
      startPursuit(buf);
    } else {
      stop(buf);
    }
  }
}

void CoverageSearchClientRos::onPerfectPerception(const hameritt::PerceptionReport::ConstPtr& msg) {
  if (!mission_ || !filter_) return;
  const double t = msg->header.stamp.toSec() - mission_start_;
  // The pursued vehicle: the sighting of the description nearest the prediction, within the
  // gate (a tracker's data association; the context describes t = 0 and the AOI only).
  const bool tracking = pursue_ && predictor_ && predictor_->tracking();
  // A track phase: the pursuit starts at the first sighting, from any camera; the claims wait
  // until the tracking camera sees each target (with ~found_by_sighting off, the ADK's find and
  // so the phase's start are the claim).
  const bool defer_claims = track_phase_ && pursue_ && predictor_ && !track_claim_camera_.empty();
  std::vector<clients::VehicleState> predicted;
  double nearest = 0.0;
  geometry::Vec3 pursued_at(0, 0, 0);  // where the pursued vehicle is predicted now
  if (tracking) {
    const double unseen = t - predictor_->last().t;
    pursued_at = predictor_->predict(t).position;
    predicted = unseen > kBranchAfter ? predictor_->hypotheses(t)
                                      : std::vector<clients::VehicleState>{predictor_->predict(t)};
    nearest = associationGate(unseen);
  }
  std::optional<std::pair<geometry::Vec3, double>> associated;
  std::string associated_description;
  bool restarted = false;
  for (const auto& e : msg->entities) {
    // Class and attributes only: the entity's id and role are ground truth a client never uses.
    const auto targets = filter_->targetsMatching(toObservation(e));
    if (targets.empty()) continue;
    const scenario::TargetDescription& target = *targets.front();
    const geometry::Vec3 p(e.position.x, e.position.y, e.position.z);
    const bool parked = parkedAt(p);
    const bool standing = standing_.observe(target.id, p, t);
    if (!parked) convoy_.observe(target.id, p, t);
    // A track phase's target not claimed yet, seen away from the pursued vehicle: kept in the
    // group view until the scored camera holds it too.
    const double from_pursued = tracking ? (pursued_at - p).head<2>().norm() : 0.0;
    if (pursuing_ && track_phase_ && track_camera_ && !parked && !track_claimed_.count(target.id) &&
        from_pursued > kSameVehicle && from_pursued <= kConvoyRadius) {
      auto& seen = unclaimed_targets_[target.id];
      if (!seen) seen = std::make_unique<clients::StreetPredictor>(*world_, pursuit_);
      seen->observe(t, p, e.yaw);
    }
    const bool pursued_look =
        pursued_description_.empty() ||
        std::any_of(targets.begin(), targets.end(),
                    [&](const auto* d) { return d->id == pursued_description_; });
    for (const auto& h : parked || !pursued_look ? std::vector<clients::VehicleState>{}
                                                 : predicted) {
      if (standing && h.speed > kDriving) continue;
      const double d = (p - h.position).head<2>().norm();
      if (d < nearest) {
        nearest = d;
        associated = std::make_pair(p, static_cast<double>(e.yaw));
        associated_description = target.id;
      }
    }
    if (pursuing_ && !defer_claims) continue;
    clients::ContextVerdict v;
    v.accepted = true;
    if (use_context_) {
      clients::CandidatePose c;
      c.position = p;
      c.yaw = e.yaw;
      c.yaw_ambiguous = false;
      c.size = clients::nominalSize(target);
      v = filter_->check(c, t, target);
    }
    if (!v.accepted) {
      ROS_INFO_THROTTLE(5.0, "%s: a %s at (%.1f, %.1f) does not fit the context: %s", kClientName,
                        clients::describe(target).c_str(), p.x(), p.y(), v.reason.c_str());
      continue;
    }
    // The first accepted sighting starts the track that a pursuit follows; on a track phase, a
    // sighting in the tracking camera restarts a track lost past its gate (not a parked car).
    const bool restart = defer_claims && tracking && lost_ && !parked &&
                         msg->camera == track_claim_camera_ &&
                         t - predictor_->last().t > kLostAfter;
    const bool at_false_lead = false_leads_.near(p.head<2>());
    const bool false_lead = !tracking && at_false_lead;
    if (pursue_ && predictor_ && (!tracking || restart) && !associated && !false_lead) {
      associated = std::make_pair(p, static_cast<double>(e.yaw));
      associated_description = target.id;
      restarted = true;
    }
    if (defer_claims) {
      // A track target is claimed once, when the tracking camera holds it: the pursued vehicle,
      // or another vehicle of a description not claimed yet that is not standing (a track target
      // drives; a parked look-alike, which the public map does not list, is not claimed) and,
      // while the pursuit holds a vehicle, drives within kConvoyRadius of it.
      const std::string& id = v.target_id.empty() ? target.id : v.target_id;
      const bool held = tracking && !lost_;
      const bool pursued = held && from_pursued <= kSameVehicle;
      const bool apart = held && from_pursued > kConvoyRadius;
      // The convoy waiting to set off: beside the held vehicle, both standing. (Else the partner
      // could not be claimed before the departure, and the area's window closes with it.)
      const bool waiting_partner = held && !pursued && from_pursued <= kConvoyWait &&
                                   predictor_->last().speed < kDriving;
      // With several targets (a convoy), one of another description sighted near it lately.
      const bool in_convoy =
          mission_->objective.targets.size() < 2 || convoy_.besideAnother(target.id, p, t);
      // Held by the camera, not glimpsed while the UAV was tilted: within a level camera's reach.
      bool held_in_view = true;
      if (track_camera_ && odom_) {
        const auto& o = odom_->pose.pose.position;
        held_in_view = std::hypot(o.x - p.x(), o.y - p.y()) <=
                       kLevelMargin * clients::levelReach(*track_camera_, o.z - p.z());
      }
      if (msg->camera != track_claim_camera_ || parked ||
          (standing && !pursued && !waiting_partner) || apart || !in_convoy || !held_in_view ||
          track_claimed_.count(id)) {
        continue;
      }
      track_claimed_.insert(id);
      // The phase starts once every target is claimed: reports from the next frame on.
      if (track_claimed_.size() >= mission_->objective.targets.size()) {
        reports_after_ = msg->header.stamp.toSec();
      }
    } else if (at_false_lead || !claims_.claim(p, t)) {
      continue;
    }
    const double confidence =
        clients::claimConfidence(1.0, v.relations_checked, v.relations_skipped);
    gate_->publish(detection_pub_,
                   makeDetection(kClientName, target, p, confidence, msg->header.stamp));
    ROS_INFO("%s: claim: %s at (%.1f, %.1f), confidence %.2f (%s)", kClientName,
             clients::describe(target).c_str(), p.x(), p.y(), confidence, v.reason.c_str());
  }
  if (associated && (restarted || pursued_description_.empty())) {
    pursued_description_ = associated_description;
  }
  // Once the ADK's target state feeds the predictor, the sightings no longer do.
  if (associated && state_target_.empty()) {
    predictor_->observe(t, associated->first, associated->second);
  }
  if (defer_claims && !pursuing_ && associated) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "first sighting at (%.1f, %.1f) from the %s camera",
                  associated->first.x(), associated->first.y(), msg->camera.c_str());
    startPursuit(buf);
  }
  if (track_phase_ && pursuing_ && tracks_pub_ && !boxes_from_detector_ && reportsDue(*msg)) {
    publishTracks(*msg,
                  associated ? std::optional<geometry::Vec3>(associated->first) : std::nullopt);
  }
}

void CoverageSearchClientRos::onTargetState(const hameritt::EntityStateArray::ConstPtr& msg) {
  if (!mission_ || !predictor_ || stopped_ || msg->entities.empty()) return;
  const double t = msg->header.stamp.toSec() - mission_start_;
  // The pursued target: the one fed before, else the found target nearest the prediction (the
  // first one while nothing is predicted).
  const hameritt::EntityState* pick = nullptr;
  double best = std::numeric_limits<double>::infinity();
  for (const auto& e : msg->entities) {
    if (!state_target_.empty()) {
      if (e.id == state_target_) pick = &e;
      continue;
    }
    const geometry::Vec3 p(e.pose.position.x, e.pose.position.y, e.pose.position.z);
    const double d =
        predictor_->tracking() ? (predictor_->predict(t).position - p).head<2>().norm() : 0.0;
    if (d < best) best = d, pick = &e;
  }
  if (!pick) return;
  for (const auto& e : msg->entities) {
    if (&e == pick) continue;
    auto& other = other_targets_[e.id];
    if (!other) other = std::make_unique<clients::StreetPredictor>(*world_, pursuit_);
    const clients::VehicleState s = toVehicleState(e, t);
    other->observe(s.t, s.position, s.yaw, s.speed);
  }
  const clients::VehicleState v = toVehicleState(*pick, t);
  // (A sighting of the same stamp may have come first: this state is dropped, the next one is
  // taken, since from now on only the state feeds the predictor.)
  predictor_->observe(v.t, v.position, v.yaw, v.speed);
  if (state_target_.empty()) {
    state_target_ = pick->id;
    ROS_INFO("%s: the ADK's target state feeds the pursuit from t %.1f: (%.1f, %.1f), %.1f m/s",
             kClientName, t, v.position.x(), v.position.y(), v.speed);
  }
  // The target found before the client's own claim (by a sighting, ~found_by_sighting), e.g.
  // while the search goes on after a false lead was set aside: the pursuit class pursues it.
  // (A track phase's pursuit waits for its claims.)
  if (!pursuing_ && pursue_ && !track_phase_ && mission_->objective.type == "track") {
    startPursuit("the ADK's target state: found");
  }
}

void CoverageSearchClientRos::onBlobs(const hameritt::PerceptionReport::ConstPtr& msg) {
  if (!mission_ || !filter_ || !track_phase_ || !pursuing_ || !tracks_pub_ || stopped_ ||
      !reportsDue(*msg)) {
    return;
  }
  const double t = msg->header.stamp.toSec() - mission_start_;
  publishTracks(*msg, predictor_->predict(t).position);
}

bool CoverageSearchClientRos::reportsDue(const hameritt::PerceptionReport& msg) const {
  if (track_claim_camera_.empty()) return true;
  return reports_after_ >= 0 && msg.header.stamp.toSec() > reports_after_;
}

bool CoverageSearchClientRos::parkedAt(const geometry::Vec3& p) const {
  return std::any_of(parked_.begin(), parked_.end(), [&](const geometry::Vec2& c) {
    return (c - p.head<2>()).norm() < kParkedRadius;
  });
}

void CoverageSearchClientRos::publishTracks(const hameritt::PerceptionReport& msg,
                                            const std::optional<geometry::Vec3>& near) {
  hameritt::TrackReport report;
  report.header.stamp = msg.header.stamp;  // the image's
  report.header.frame_id = msg.header.frame_id;
  report.camera = msg.camera;
  std::map<std::string, std::pair<double, hameritt::TrackedBox>> best;  // target id -> box
  for (const auto& e : msg.entities) {
    const geometry::Vec3 p(e.position.x, e.position.y, e.position.z);
    const bool parked = parkedAt(p);
    if (parked) continue;
    for (const auto* target : filter_->targetsMatching(toObservation(e))) {
      const double d = near ? (p - *near).head<2>().norm() : 0.0;
      const auto it = best.find(target->id);
      if (it != best.end() && it->second.first <= d) continue;
      hameritt::TrackedBox b;
      b.target_id = target->id;
      b.x = e.box.x_min;
      b.y = e.box.y_min;
      b.w = e.box.x_max - e.box.x_min + 1;
      b.h = e.box.y_max - e.box.y_min + 1;
      best[target->id] = {d, b};
    }
  }
  for (const auto& kv : best) report.tracks.push_back(kv.second.second);
  gate_->publish(tracks_pub_, report);
}

void CoverageSearchClientRos::onTick() {
  if (!mission_ || stopped_) return;
  if (mission_->time_limit > 0 && missionTime() > mission_->time_limit) {
    stop("the mission's time limit has passed");
    return;
  }
  sendIfDue();
}

void CoverageSearchClientRos::startPursuit(const std::string& why) {
  if (pursuing_ || stopped_) return;
  pursuing_ = true;
  planner_flying_ = true;  // the search leg: stopped on the first pursuit tick
  planner_sent_at_ = -1e9;
  lost_ = false;
  losses_ = 0;
  false_leads_.restart();
  pursuit_started_at_ = missionTime();
  tilt_.reset();
  const auto& s = predictor_->last();
  ROS_INFO("%s: %s: pursuing it from (%.1f, %.1f), %.1f m/s, standoff %.1f m, height %.1f m",
           kClientName, why.c_str(), s.position.x(), s.position.y(), s.speed, pursuit_.standoff,
           pursuit_.height);
}

// A pursuit lost before the find was confirmed: set the lead aside and go on with the search.
void CoverageSearchClientRos::abandonPursuit(double t) {
  const geometry::Vec2 lead = predictor_->last().position.head<2>();
  false_leads_.setAside(lead);
  ROS_INFO("%s: pursuit: not confirmed %.1f s after it started (last seen %.1f s ago): back to "
           "the search (the lead at (%.1f, %.1f) set aside, %zu in all)",
           kClientName, t - pursuit_started_at_, t - predictor_->last().t, lead.x(), lead.y(),
           false_leads_.size());
  pursuing_ = false;
  lost_ = false;
  predictor_ = std::make_unique<clients::StreetPredictor>(*world_, pursuit_);
  pursued_description_.clear();
  unclaimed_targets_.clear();
  other_targets_.clear();
  // The search planned again from here and now (past the areas' windows, a track mission's
  // search covers the areas regardless); the planner takes the UAV over.
  exhausted_ = false;
  replan("a false lead set aside");
}

void CoverageSearchClientRos::onPursuitTick() {
  if (!pursuing_ || stopped_ || !odom_ || !chooser_) return;
  const double t = missionTime();
  const auto& o = odom_->pose.pose.position;
  const geometry::Vec3 uav(o.x, o.y, o.z);
  const double unseen = t - predictor_->last().t;
  if (unseen > kLostAfter && !lost_) {
    lost_ = true;
    ++losses_;
    ROS_INFO("%s: pursuit: lost the target (loss %d); flying to its prediction", kClientName,
             losses_);
  } else if (unseen <= kLostAfter && lost_) {
    lost_ = false;
    ROS_INFO("%s: pursuit: reacquired the target after loss %d", kClientName, losses_);
  }
  // Lost: climb (up to 15 m) for a wider view around the prediction.
  double climb = lost_ ? std::min(15.0, 2.0 * (unseen - kLostAfter)) : 0.0;
  // Lost, it flies to where the vehicle must pass: the next intersection with a choice.
  clients::VehicleState v = lost_ ? predictor_->predictToJunction(t + pursuit_.lead)
                                  : predictor_->predict(t + pursuit_.lead);
  const bool confirmed = !state_target_.empty() || (track_phase_ && !track_claimed_.empty());
  // (A track phase's pursuit starts before its claims, at the first sighting.)
  const bool state_expected = !track_phase_ && use_target_state_ && target_state_sub_ &&
                              target_state_sub_.getNumPublishers() > 0;
  const double confirm_by = state_expected ? pursuit_started_at_ + kConfirmWait
                                           : std::numeric_limits<double>::infinity();
  if (false_leads_.giveUp(t, lost_, confirmed, uav.head<2>(), v.position.head<2>(), confirm_by)) {
    abandonPursuit(t);
    return;
  }
  // The vehicle's own velocity (a group's centre below takes a yaw across the vehicles' line).
  const geometry::Vec2 vehicle_velocity =
      v.speed * geometry::Vec2(std::cos(v.yaw), std::sin(v.yaw));
  // A track phase with several targets in the ADK's state: all of them in the scored camera,
  // from above their midpoint, high enough to hold them across the image.
  bool grouped = false;
  if (track_phase_ && !lost_ && track_camera_) {
    std::vector<clients::VehicleState> group{v};
    for (const auto& kv : other_targets_) {
      const clients::StreetPredictor& other = *kv.second;
      if (t - other.last().t <= kLostAfter) group.push_back(other.predict(t + pursuit_.lead));
    }
    for (const auto& kv : unclaimed_targets_) {
      const clients::StreetPredictor& other = *kv.second;
      if (!track_claimed_.count(kv.first) && t - other.last().t <= kLostAfter) {
        group.push_back(other.predict(t + pursuit_.lead));
      }
    }
    if (group.size() > 1) {
      grouped = true;
      const clients::GroupView g = clients::groupView(group, *track_camera_, kGroupMargin);
      v = g.centre;
      climb = std::max(climb, g.height - pursuit_.height);
    }
  }
  clients::PursuitView view = chooser_->choose(v, uav, t, climb);
  if (track_phase_ && track_camera_) {
    // The UAV tilts into its flight and the nadir camera with it: fly the difference ahead, so
    // that the tilted axis, not the point below the UAV, lies on the target. Averaged over
    // about 4 s: the tilt that flying ahead itself causes (a speed-up, then braking) averages
    // out, the steady tilt against drag and wind stays (a shorter average fed back on itself:
    // speeding up tilts more, which moves the viewpoint farther ahead).
    // Only the tilt of keeping station counts (clients::TiltAverage): moving with the vehicle,
    // near where the autopilot's lag puts a UAV sent `lead` seconds ahead of it; not that of
    // catching up, braking or circling.
    const auto& q = odom_->pose.pose.orientation;
    const Eigen::Quaterniond attitude = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized();
    const geometry::Vec3 uav_velocity = worldVelocityOf(*odom_);
    const geometry::Vec2 shift =
        clients::tiltedAxisShift(*track_camera_, attitude, uav.z() - v.position.z());
    view.position.head<2>() -=
        tilt_.update(uav.head<2>(), uav_velocity.head<2>(),
                     view.position.head<2>() - tilt_.shift() - pursuit_.lead * vehicle_velocity,
                     vehicle_velocity, shift);
    // Straight above one vehicle, the image's wider axis along its way (as the group view lays
    // it along the cars' line): the leading edge is then half the horizontal field ahead, not
    // half the vertical one.
    if (!grouped && (view.position - v.position).head<2>().norm() < 12.0) {
      view.yaw = std::remainder(v.yaw + 0.5 * geometry::kPi, 2.0 * geometry::kPi);
    }
  }
  const ros::Time now = ros::Time::now();
  ROS_INFO_THROTTLE(10.0,
                    "%s: pursuit t %.1f: UAV (%.1f, %.1f, %.1f), last sighting %.1f s ago at "
                    "(%.1f, %.1f) %.1f m/s, viewpoint (%.1f, %.1f, %.1f)%s",
                    kClientName, t, uav.x(), uav.y(), uav.z(), unseen,
                    predictor_->last().position.x(), predictor_->last().position.y(),
                    predictor_->last().speed, view.position.x(), view.position.y(),
                    view.position.z(), view.visible ? "" : ", no line of sight");
  // Straight at the viewpoint when nothing lies between; in the city a building can. The
  // straight flight keeps 3 m from the walls: the viewpoint moves while the UAV flies at it, and
  // a UAV at speed close beside a wall has no room to turn when the planner takes over.
  if (chooser_->kozClear(uav, view.position, t) &&
      obstacles_->obstacleSegmentClear(uav, view.position, -kStraightClearance)) {
    if (planner_flying_) {
      nav_msgs::Path stop_planner;  // empty: the planner stops following
      stop_planner.header.stamp = now;
      stop_planner.header.frame_id = "map";
      gate_->publish(waypoints_pub_, stop_planner);
      planner_flying_ = false;
    }
    gate_->publish(pose_pub_, poseAt(view.position, view.yaw, now));
  } else if (t - planner_sent_at_ > 3.0) {
    // A keep-out zone or a building lies between: the planner finds the way round.
    nav_msgs::Path path;
    path.header.stamp = now;
    path.header.frame_id = "map";
    path.poses.push_back(poseAt(view.position, now));
    gate_->publish(waypoints_pub_, path);
    planner_flying_ = true;
    planner_sent_at_ = t;
  }
}

void CoverageSearchClientRos::onTraffic(const hameritt::EntityStateArray::ConstPtr& msg) {
  if (!avoid_) return;
  const double t = msg->header.stamp.toSec() - mission_start_;
  for (const auto& e : msg->entities) {
    clients::TrafficReport r;
    r.id = e.id;
    r.t = t;
    // The message gives the bottom of the box; the pilot predicts body centres.
    r.position =
        geometry::Vec3(e.pose.position.x, e.pose.position.y, e.pose.position.z + 0.5 * e.size.z);
    r.velocity = geometry::Vec3(e.velocity.linear.x, e.velocity.linear.y, e.velocity.linear.z);
    avoid_->observe(r);
  }
}

void CoverageSearchClientRos::onAvoidTick() {
  if (!avoid_ || stopped_ || !odom_) return;
  const auto& o = odom_->pose.pose.position;
  const geometry::Vec3 uav(o.x, o.y, o.z);
  const ros::Time now = ros::Time::now();
  if (!avoid_planned_) {
    avoid_planned_ = true;
    if (!avoid_->plan(uav)) {
      ROS_ERROR("%s: avoid: no flight to the goal: %s", kClientName, avoid_->why().c_str());
      avoid_.reset();
      stop("no flight to the goal");
      return;
    }
    nav_msgs::Path stop_planner;  // empty: the planner stops following
    stop_planner.header.stamp = now;
    stop_planner.header.frame_id = "map";
    gate_->publish(waypoints_pub_, stop_planner);
    ROS_INFO("%s: avoid: flying a %.1f m path of %zu points to the goal", kClientName,
             avoid_->pathLength(), avoid_->path().size());
  }
  const int replans = avoid_->replans();
  const clients::AvoidCommand c = avoid_->step(missionTime(), uav);
  if (avoid_->replans() > replans) {
    ROS_INFO("%s: avoid t %.1f: %s (%.1f m, replan %d)", kClientName, missionTime(),
             c.reason.c_str(), avoid_->pathLength(), avoid_->replans());
  }
  if (c.at_goal && !avoid_arrived_) {
    avoid_arrived_ = true;
    ROS_INFO("%s: avoid: the reference is at the goal", kClientName);
  }
  if (c.conflict) {
    ROS_INFO_THROTTLE(2.0, "%s: avoid t %.1f: %s", kClientName, missionTime(), c.reason.c_str());
  } else {
    ROS_INFO_THROTTLE(10.0, "%s: avoid t %.1f: UAV (%.1f, %.1f, %.1f), %zu aircraft reported, %s",
                      kClientName, missionTime(), uav.x(), uav.y(), uav.z(), avoid_->tracked(),
                      c.reason.c_str());
  }
  gate_->publish(pose_pub_, poseAt(c.setpoint, c.yaw, now));
}

void CoverageSearchClientRos::stop(const std::string& why) {
  if (stopped_) return;
  stopped_ = true;
  if (pursuing_) {
    ROS_INFO("%s: pursuit over: the target was lost %d times", kClientName, losses_);
  }
  pursuing_ = false;
  ROS_INFO("%s: stopping the search: %s", kClientName, why.c_str());
  nav_msgs::Path path;
  path.header.stamp = ros::Time::now();
  path.header.frame_id = "map";
  // Hover where the UAV is (an empty list when it is still on the ground: stay there).
  if (odom_ && odom_->pose.pose.position.z > 1.0) {
    const auto& p = odom_->pose.pose.position;
    const double z = std::clamp(p.z, sim_.uav.altitude_min + 1.5, sim_.uav.altitude_max - 1.5);
    path.poses.push_back(poseAt(geometry::Vec3(p.x, p.y, z), path.header.stamp));
  }
  gate_->publish(waypoints_pub_, path);
}

void CoverageSearchClientRos::publishPlan() {
  nav_msgs::Path path;
  path.header.stamp = ros::Time::now();
  path.header.frame_id = "map";
  for (const auto& leg : plan_.legs) {
    for (const auto& w : leg.waypoints) {
      path.poses.push_back(poseAt(w.position, ros::Time(std::max(0.0, w.eta + mission_start_))));
    }
  }
  gate_->publish(plan_pub_, path);
}

}  // namespace hameritt::ros_wrappers
