#pragma once
// The ADK node: the ROS API that client algorithms touch. It publishes the mission (never the
// targets' positions) and the UAV's envelope (/mission/uav), monitors the flown path against
// the keep-out zones and areas of interest, gives perfect perception from the renderer's boxes
// in maneuver-only runs, scores detection claims, and judges the mission's lifecycle and metrics
// (metrics.json). The logic is the ROS-free hameritt_adk library; this class wires topics to it.
// See docs/reference/client-contract.md.

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hameritt/BoundingBoxArray.h"
#include "hameritt/CrashEvent.h"
#include "hameritt/Detection.h"
#include "hameritt/EntityStateArray.h"
#include "hameritt/FollowStatus.h"
#include "hameritt/PhaseState.h"
#include "hameritt/SimulationEnd.h"
#include "hameritt/TrackReport.h"
#include "hameritt/TrackStatus.h"
#include "hameritt/adk/clock_watchdog.h"
#include "hameritt/adk/constraint_monitor.h"
#include "hameritt/adk/coverage.h"
#include "hameritt/adk/detection_scoring.h"
#include "hameritt/adk/metrics.h"
#include "hameritt/adk/target_view.h"
#include "hameritt/ros/lockstep.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::ros_wrappers {

// Parameters (private namespace):
//   ~mission, ~sim_config (paths, required), ~output_dir ("" = no metrics.json),
//   ~mode (maneuver_only | perception_only | end_to_end; maneuver_only),
//   ~perfect_perception (default: mode == maneuver_only), ~min_visible_pixels (20),
//   ~status_rate_hz (10, sim time), ~shutdown_on_end (true), ~end_linger (1.0 wall s),
//   ~time_limit (mission.time_limit), ~car_gate (6), ~pedestrian_gate (3),
//   ~found_by_sighting (default: mode == maneuver_only), ~track_fraction (0.5),
//   ~coverage_cell_size (2), ~coverage_max_range (150),
//   ~recorder_min_space_mb (0 = no recorder; else the recorder's --min-space in MB: a mission
//   cut short while ~output_dir's disk has less free names the recorder's stop as the cause),
//   ~traffic_rate_hz (2, sim time; 0 = none: an avoid mission's aircraft as ADS-B-like reports
//   on adk/traffic, hameritt/EntityStateArray, class and role "aircraft", at the odometry after
//   each period),
//   ~track_camera (the camera whose frames score a track phase: "down" when the UAV has it, else
//   the first camera).
// Topics are relative to the node's namespace (/mission, /adk/... in the root namespace).
class AdkRos {
 public:
  // Throws scenario::ConfigError (bad parameters, mission or sim_config): the node exits 1.
  AdkRos(ros::NodeHandle& nh, ros::NodeHandle& pnh);

  // Serves callbacks until the mission has ended and (shutdown_on_end) its metrics have been
  // published for ~end_linger wall seconds, or until ROS shuts down or a signal arrives
  // (outcome aborted if the mission had not ended). Metrics are written either way. Returns the
  // process exit code (0; 1 if metrics.json could not be written).
  int spin();

  // Called by the node's SIGINT/SIGTERM handler (async-signal-safe: sets a flag).
  static void requestStop();

 private:
  void onClock(const rosgraph_msgs::Clock::ConstPtr& msg);
  void onOdometry(const nav_msgs::Odometry::ConstPtr& msg);
  void onTruth(const hameritt::EntityStateArray::ConstPtr& msg);
  // adk/target_state: the found targets' entries of a ground-truth message, at its rate.
  void publishTargetState(const hameritt::EntityStateArray& truth);
  void onCrash(const hameritt::CrashEvent::ConstPtr& msg);
  void onBoxes(std::size_t camera, const hameritt::BoundingBoxArray::ConstPtr& msg);
  void onDetection(const hameritt::Detection::ConstPtr& msg);
  // A client's track report (perception/tracks): fed to the track phase's scorer.
  void onTracks(const hameritt::TrackReport::ConstPtr& msg);
  // The track phase's frame of camera `camera`: the targets' boxes, visible fractions and
  // occlusion from the instance mask (targets without a visible pixel are absent).
  void addTrackFrame(const hameritt::BoundingBoxArray& msg);
  // The simulator stopped at its duration: the mission ends (outcome ended) once the odometry
  // up to that time has been handled (at once in lock-step; free running, within a wall second).
  void onSimulationEnd(const hameritt::SimulationEnd::ConstPtr& msg);
  void endAtSimulationEnd(bool force);
  // "" or "recorder stopped: less than N MB free on the output disk (...)".
  std::string recorderDiskShortage() const;

  // Scenario entities at time t (ground truth history when there is one, else their
  // sim_config trajectories) and parked world cars.
  std::vector<adk::EntityTruth> truthAt(double t) const;
  void publishState();
  void publishConstraints(double t);
  void checkObjective(double t);
  // At the find of every target (mission running, the phase not yet started): publishes the
  // search phase's success and `phase` active on adk/phase and says how the targets were found
  // ("target sighted", "targets claimed", ...); otherwise nothing.
  std::optional<std::string> phaseStartsAtFind(double t, bool started,
                                               const scenario::MissionPhase& phase);
  // Avoid missions: ends the mission once the goal is reached, succeeded when the avoid phase's
  // criteria hold (adk/avoid_score.h), failed otherwise.
  void checkAvoid(double t);
  // adk/avoid: the avoid phase's score `a` at sim time t.
  void publishAvoid(double t, const adk::AvoidScore& a);
  adk::TrafficSample avoidSample(double t, const Eigen::Vector3d& p,
                                 const Eigen::Vector3d& v) const;
  // adk/traffic: the aircraft of sample `s` as ADS-B-like reports (hameritt/EntityStateArray).
  void publishTraffic(double t, const adk::TrafficSample& s);
  // Track objectives are judged at the time limit: at t >= the limit, success when every
  // target was in view for the track fraction of it (before the time limit's timeout).
  void judgeTrackAtLimit(double t);
  // Follow missions: the search phase ends at the find, which starts the follow phase; the
  // mission ends when the follow phase has run its duration (succeeded when its criteria hold,
  // adk/follow_score.h) or has been outside its envelope too long (failed).
  void checkFollow(double t);
  // adk/follow: the follow phase's score `f` at sim time t.
  void publishFollow(double t, const adk::FollowPhaseScore& f);
  // adk/phase: `phase` entered `state` at sim time t.
  void publishPhase(double t, const scenario::MissionPhase& phase, adk::PhaseState state,
                    const std::string& reason);
  adk::FollowPhaseScore followScore(bool ended) const;
  // Track missions: the search phase ends at the find, which starts the track phase; the
  // mission ends when the track phase has run its duration (succeeded when its criteria hold,
  // adk/track_score.h) or a target has been lost too long (failed).
  void checkTrack(double t);
  // adk/track: the track phase's score `s` at sim time t.
  void publishTrack(double t, const adk::TrackPhaseScore& s);
  // Ends the mission (lifecycle already ended): metrics.json, /adk/metrics, /adk/state.
  void finish();

  // Configuration.
  scenario::Mission mission_;
  scenario::SimConfig sim_config_;
  // First, destroyed last: the subscriptions and periodic work go through it.
  std::unique_ptr<LockstepGate> gate_;
  std::unique_ptr<scenario::World> world_;
  std::string mode_, output_dir_;
  bool perfect_perception_ = false;
  bool found_by_sighting_ = false;
  int min_visible_pixels_ = 20;
  double status_period_ = 0.1;
  bool shutdown_on_end_ = true;
  double end_linger_ = 1.0;
  double coverage_max_range_ = 150.0;
  double recorder_min_space_mb_ = 0.0;
  std::vector<adk::CameraIntrinsics> intrinsics_;
  std::map<std::string, std::size_t> scenario_index_;  // scenario entity id -> sim_config index
  // The avoid mission's aircraft of that id (sim_config.json aircraft), or null.
  const scenario::Aircraft* aircraftById(const std::string& id) const;
  std::vector<adk::EntityTruth> world_cars_;
  std::map<std::string, std::size_t> world_car_index_;

  // Core objects.
  std::unique_ptr<adk::ConstraintMonitor> monitor_;
  std::unique_ptr<adk::CoverageGrid> coverage_;
  std::unique_ptr<adk::DetectionScorer> scorer_;
  std::unique_ptr<adk::MetricsAccumulator> metrics_;
  std::unique_ptr<adk::MissionLifecycle> lifecycle_;
  // The avoid phase of an avoid mission: scored from the odometry and the scripted aircraft.
  std::unique_ptr<adk::AvoidScorer> avoid_;
  std::string avoid_phase_;
  // The follow phase of a follow mission (after its search phase): scored from the odometry and
  // the target's scripted trajectory, line of sight against the world's occluders.
  std::unique_ptr<adk::FollowScorer> follow_;
  const scenario::MissionPhase* search_phase_ = nullptr;
  const scenario::ScenarioEntity* follow_target_ = nullptr;
  double follow_koz_start_ = 0.0;  // the monitor's violation seconds at the phase's start
  // The track phase of a track mission (after its search phase): scored from the frames of
  // camera track_camera_ and the client's reports.
  std::unique_ptr<adk::TrackScorer> track_;
  std::size_t track_camera_ = 0;
  // The UAV's recent odometry poses: where the track camera was at each frame's stamp, to
  // project the targets the renderer gave no box (adk/target_view.h).
  adk::PoseHistory poses_{5.0};
  bool crashed_ = false;
  std::map<std::string, adk::PhaseState> phase_states_;  // the last published, by phase id
  double traffic_period_ = 0.5;                          // s between adk/traffic reports; 0: none
  double next_traffic_t_ = 0.0;
  std::unique_ptr<adk::ClockWatchdog> watchdog_;
  adk::GroundTruthHistory truth_{10.0};

  // Run state.
  bool have_odom_ = false;
  double last_odom_t_ = 0.0;
  double now_ = 0.0;  // latest sim time seen (clock or odometry)
  double next_status_t_ = 0.0;
  std::vector<double> next_footprint_t_;
  bool finished_ = false;
  bool write_failed_ = false;
  // adk/target_state: its period (0: off) and the sim time of the next message.
  double target_state_period_ = 0.0;
  double next_target_state_t_ = 0.0;
  // The simulator's end, waiting for the odometry up to its time.
  bool sim_end_pending_ = false;
  double sim_end_t_ = 0.0;
  std::string sim_end_reason_;
  ros::WallTime sim_end_seen_;
  ros::WallTime finished_at_;

  ros::Publisher mission_pub_, markers_pub_, uav_pub_, constraints_pub_, events_pub_,
      perception_pub_, scores_pub_, state_pub_, metrics_pub_, avoid_pub_, follow_pub_, phase_pub_,
      traffic_pub_, track_pub_, target_state_pub_;
  ros::Subscriber clock_sub_, odom_sub_, truth_sub_, crash_sub_, detection_sub_, sim_end_sub_,
      tracks_sub_;
  std::vector<ros::Subscriber> box_subs_;
};

}  // namespace hameritt::ros_wrappers
