#pragma once
// The baseline maneuver client: a prior-weighted coverage search (clients::planSearch) of the
// mission's areas of interest and route bands, flown through the planner's waypoint follower one
// leg at a time; it hovers when the ADK says the mission is over, at the mission's time limit, or
// once the objective's targets have been detected. A track objective (pursuit) is not over at
// the find: the client then pursues the target (clients::ViewpointChooser, StreetPredictor) until
// the mission ends. An avoid mission (a reach objective with an avoid phase) is flown by
// clients::AvoidPilot instead of a search: the shortest flight to the goal, deconflicted from the
// aircraft of the ADK's traffic reports and the moving keep-out zones. In maneuver-only mode it
// also turns the ADK's perfect perception into claims (the paper's maneuver-only training
// thread).

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <topic_tools/shape_shifter.h>

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>

#include "hameritt/Detection.h"
#include "hameritt/EntityStateArray.h"
#include "hameritt/FollowProgress.h"
#include "hameritt/Mission.h"
#include "hameritt/PerceptionReport.h"
#include "hameritt/TrackReport.h"
#include "hameritt/clients/avoid.h"
#include "hameritt/clients/claims.h"
#include "hameritt/clients/context_filter.h"
#include "hameritt/clients/coverage.h"
#include "hameritt/clients/pursuit.h"
#include "hameritt/ros/lockstep.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::ros_wrappers {

// Topics (relative names): sub mission (hameritt/Mission, latched), uav/odom, planner/progress,
// adk/state (any type), perception/detections; pub planner/waypoints (nav_msgs/Path), ~plan
// (nav_msgs/Path, latched: every waypoint of the current plan), uav/cmd_pose while pursuing
// (geometry_msgs/PoseStamped); in maneuver-only mode sub adk/perfect_perception and pub
// perception/detections; while pursuing sub adk/target_state (hameritt/EntityStateArray).
//
// Parameters (private): ~sim_config (required; only its public part is read:
// clients::loadPublicSimConfig), ~camera ("down"), ~altitude (0: highest that keeps a car's width
// at ~min_car_pixels, 25), ~overlap (0.2), ~koz_margin (3 m), ~max_leg_waypoints (12),
// ~cover_zero_cells (false), ~repeat (true: sweep again when everything open has been swept),
// ~stop_on_detection (true), ~claim_from_perfect_perception (false), ~use_context (true: claims
// must pass the context filter), ~claim_radius (4 m), ~claim_hold (30 s), ~mission_start_time
// (0: sim time of mission time 0), ~rate_hz (2), ~pursue (true: pursue a track objective's
// target after its find instead of hovering), ~pursuit_standoff (8 m), ~pursuit_height (20 m),
// ~pursuit_lead (1 s), ~pursuit_rate_hz (10), ~publish_tracks (true: on a track phase, while
// pursuing, each target's box goes out on perception/tracks), ~track_boxes (perfect_perception:
// the boxes of adk/perfect_perception | detector: those of the detector's perception/blobs,
// hameritt/PerceptionReport, nearest the pursued vehicle's predicted position), ~avoid (true: fly
// an avoid mission with the pilot), ~avoid_rate_hz (10), ~avoid_speed_fraction (0.6),
// ~avoid_horizontal_buffer (9 m), ~avoid_vertical_buffer (6 m), ~avoid_horizon (10 s),
// ~track_claim_camera ("down": on a track phase, each target is claimed once, when this
// camera sees it, the pursuit starting at the first sighting, and the viewpoints are chosen
// for this camera alone; "": claims and viewpoints as in the other classes), ~track_standoff
// (0 m: on a track phase, this far behind the predicted vehicle, ~pursuit_height above it),
// ~use_target_state (true: while pursuing, the pursued target's state on adk/target_state,
// published in maneuver_only from its find on, feeds the prediction instead of the
// sightings), ~drive_off_speed (track missions; 13 m/s, the generator's fastest car: once the
// search goes on past the areas' windows, a sighting that far from its area per second since the
// window closed still passes the context filter). Avoid
// missions: sub adk/traffic (hameritt/EntityStateArray), pub uav/cmd_pose.
class CoverageSearchClientRos {
 public:
  // Throws scenario::ConfigError for bad parameters or files (the node exits with ROS_FATAL).
  CoverageSearchClientRos(ros::NodeHandle& nh, ros::NodeHandle& pnh);
  // Serves callbacks until shutdown (in turns when ~lockstep).
  void spin() { gate_->spin(); }

 private:
  void onMission(const hameritt::Mission::ConstPtr& msg);
  void onOdometry(const nav_msgs::Odometry::ConstPtr& msg);
  void onProgress(const hameritt::FollowProgress::ConstPtr& msg);
  void onState(const topic_tools::ShapeShifter::ConstPtr& msg);
  void onDetection(const hameritt::Detection::ConstPtr& msg);
  // With ~track_claim_camera: a frame after the one that claimed the last target (the phase
  // starts at that claim), so that no report precedes the phase.
  bool reportsDue(const hameritt::PerceptionReport& msg) const;
  // A sighting at p is a parked car of the public map.
  bool parkedAt(const geometry::Vec3& p) const;
  // perception/tracks: for each mission target, the box of the sighting in `msg` that matches
  // its description, is not a parked car of the public map, and lies nearest `near` (the
  // pursued vehicle) when there is one.
  void publishTracks(const hameritt::PerceptionReport& msg,
                     const std::optional<geometry::Vec3>& near);
  void onPerfectPerception(const hameritt::PerceptionReport::ConstPtr& msg);
  // adk/target_state (maneuver_only, ~use_target_state): the pursued target's ground-truth
  // state goes to the predictor as a sighting with its heading and speed; from then on it
  // alone feeds the predictor.
  void onTargetState(const hameritt::EntityStateArray::ConstPtr& msg);
  // ~track_boxes detector: the detector's blobs of a frame become the track report, each
  // target's the blob nearest the pursued vehicle's predicted position.
  void onBlobs(const hameritt::PerceptionReport::ConstPtr& msg);
  void onTick();
  // Pursuit: starts it (after the find of a track objective's target) and flies it.
  void startPursuit(const std::string& why);
  void onPursuitTick();
  void abandonPursuit(double t);
  // Avoid: traffic reports and the pilot's tick.
  void onTraffic(const hameritt::EntityStateArray::ConstPtr& msg);
  void onAvoidTick();

  double missionTime() const;
  void replan(const std::string& why);
  // Sends the current leg when it is due; ends the search when the plan is spent.
  void sendIfDue();
  void legFailed(const hameritt::FollowProgress& msg);
  // Hovers where the UAV is and stops searching.
  void stop(const std::string& why);
  void publishPlan();

  scenario::SimConfig sim_;  // public part only
  // First, destroyed last: the subscriptions and the tick go through it.
  std::unique_ptr<LockstepGate> gate_;
  std::unique_ptr<scenario::World> world_;
  // The world's obstacles with the follower's default margin: sweep waypoints inside a building
  // are lifted over its roof (clients::clearWaypoints).
  std::unique_ptr<planning::WorldValidity> obstacles_;
  const scenario::World* context_world_ = nullptr;  // world_ where the claims use the context
  clients::CoverageSettings settings_;
  std::optional<scenario::Mission> mission_;
  // Once the search goes on past the areas' windows, the context filter accepts a sighting
  // within this reach (m/s past the window's end) of its area: the target may have driven off.
  double drive_off_speed_ = 13.0;
  std::unique_ptr<clients::ContextFilter> filter_;
  bool repeat_ = true, stop_on_detection_ = true, claim_ = false, use_context_ = true;
  double mission_start_ = 0.0;

  std::optional<nav_msgs::Odometry> odom_;
  clients::SearchPlan plan_;
  std::size_t leg_ = 0;
  std::set<std::string> covered_;
  bool planned_ = false, sent_ = false, acked_ = false, stopped_ = false, exhausted_ = false;
  int failures_ = 0;
  double retry_at_ = 0.0;
  clients::ClaimLedger claims_;
  clients::ClaimLedger detections_;
  clients::StandingSightings standing_;  // where look-alikes of each description stand

  // Pursuit.
  bool pursue_ = true, pursuing_ = false, planner_flying_ = false, lost_ = false;
  clients::PursuitSettings pursuit_;
  std::unique_ptr<clients::StreetPredictor> predictor_;
  std::unique_ptr<clients::ViewpointChooser> chooser_;
  std::vector<geometry::Vec2> parked_;  // the public map's parked cars
  double planner_sent_at_ = -1e9;
  int losses_ = 0;
  // ~use_target_state: the ADK's ground-truth state of the found targets feeds the predictor.
  bool use_target_state_ = true;
  // The target whose state feeds the predictor (empty until the first adk/target_state), and
  // the other found targets' predictions (a track phase keeps them all in view).
  std::string state_target_;
  // The target description the pursuit follows (its first sighting's, or a restart's): only its
  // sightings are associated with the prediction, so a look-alike of another target's
  // description driving by does not take the pursuit over.
  std::string pursued_description_;
  // The sightings of the targets' descriptions (not parked) lately: a track phase's targets
  // drive as a convoy, so one is claimed only beside another's sighting.
  clients::ConvoySightings convoy_;
  std::map<std::string, std::unique_ptr<clients::StreetPredictor>> other_targets_;
  // A track phase's targets (by description) sighted away from the pursued vehicle and not yet
  // claimed: the group view brings them into the scored camera.
  std::map<std::string, std::unique_ptr<clients::StreetPredictor>> unclaimed_targets_;
  // A track phase's scored camera when it looks straight down (the group view needs that).
  std::optional<scenario::CameraSpec> track_camera_;
  // A track phase: metres behind the predicted vehicle (0: straight above it), where the
  // scored camera (~track_claim_camera) looks down on it.
  double track_standoff_ = 0.0;
  // The smoothed ground shift of the scored camera's axis by the UAV's tilt (tiltedAxisShift).
  clients::TiltAverage tilt_;
  // Where pursuits lost before their find was confirmed last saw their vehicle (a look-alike, or
  // a glimpse that drove off); a sighting there starts no pursuit and no claim again.
  clients::FalseLeads false_leads_;
  double pursuit_started_at_ = 0.0;  // mission time

  // Avoid.
  bool avoid_enabled_ = true, avoid_planned_ = false, avoid_arrived_ = false;
  clients::AvoidSettings avoid_settings_;
  std::unique_ptr<clients::AvoidPilot> avoid_;

  ros::Publisher waypoints_pub_, plan_pub_, detection_pub_, pose_pub_, tracks_pub_;
  // A track phase: while pursuing, the boxes of the targets it sees go out on perception/tracks.
  bool publish_tracks_ = true;
  // Where the reported boxes come from: false, perfect perception; true, the detector's blobs.
  bool boxes_from_detector_ = false;
  bool track_phase_ = false;
  // A track phase: each target is claimed once, when this camera sees it ("": at every sighting,
  // as in the other classes); the pursuit starts at the first sighting from any camera.
  std::string track_claim_camera_ = "down";
  std::set<std::string> track_claimed_;
  double reports_after_ = -1.0;  // the stamp of the frame that claimed the last target
  ros::Subscriber mission_sub_, odom_sub_, progress_sub_, state_sub_, detection_sub_, perfect_sub_,
      traffic_sub_, blobs_sub_, target_state_sub_;
};

}  // namespace hameritt::ros_wrappers
