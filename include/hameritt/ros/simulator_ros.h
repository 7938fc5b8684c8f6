#pragma once
// ROS wrapper of the simulator core: sim time on /clock, UAV odometry/IMU/tf, ground truth,
// velocity and pose setpoints, pause/resume, lock-step stepping and reset.

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <memory>
#include <string>

#include "hameritt/ResetSimulation.h"
#include "hameritt/SetPaused.h"
#include "hameritt/StepSimulation.h"
#include "hameritt/ros/camera_rig.h"
#include "hameritt/ros/lockstep.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"
#include "hameritt/sim/setpoint_guard.h"
#include "hameritt/sim/simulator.h"
#include "hameritt/sitl/ardupilot_server.h"
#include "hameritt/sitl/gcs_telemetry.h"
#include "hameritt/sitl/px4_server.h"

namespace hameritt::ros_wrappers {

// Parameters (private namespace):
//   ~sim_config (path, required), ~urdf (default: the package's models/sentinel.urdf),
//   ~physics_rate_hz (500), ~real_time_factor (0 = as fast as possible), ~start_paused (false),
//   ~publish_rate_hz (250: /clock, odometry, IMU, UAV tf), ~ground_truth_rate_hz (20),
//   ~duration (0 = the scenario's; free running stops there and the node stays up),
//   ~cameras (true: render and publish the payload cameras), ~render_backend (auto |
//   surfaceless | device), ~camera_weather (true), ~camera_noise (true), ~render_queue_depth (2),
//   ~render_lod_px (0.5: far instances drawn with coarse meshes whose deviation projects to at
//   most this many pixels; 0 = full detail), ~render_threads (2: frame sets rendered
//   concurrently, each thread with its own renderer, published in order),
//   ~record_image_rate (0: also publish camera images decimated to this rate for recording),
//   ~wait_for (comma-separated topics of this node; the clock starts once each has a
//   subscriber, or after ~wait_timeout wall seconds, 60), ~wait_for_nodes (comma-separated
//   node names, e.g. the mission's clients: the clock also waits until the master knows each,
//   within the same timeout), ~geofence_margin (50 m: the UAV is
//   kept inside the neighborhood bounds grown by this and below altitude_max + this),
//   ~lockstep (false: README "Lock-step missions"; the simulator coordinates the turns of
//   ~lockstep_participants, comma-separated node names in turn order, every ~lockstep_period
//   s of sim time, 0.02, a multiple of the publish period; ~lockstep_timeout wall s, 120),
//   ~autopilot (internal: the built-in controller flies the ADK's setpoints; px4: PX4 SITL
//   flies the UAV through the simulator API on TCP ~px4_port (4560) + ~instance (0);
//   ardupilot: ArduPilot SITL through its JSON interface on UDP ~ardupilot_port (9002) +
//   10 x ~instance; with internal, ~gcs_udp (127.0.0.1:14550, off: none) receives HEARTBEAT,
//   ATTITUDE and GLOBAL_POSITION_INT at ~gcs_rate_hz (10); the
//   ~sitl_* parameters in docs/reference/nodes.md).
class SimulatorRos {
 public:
  // Throws scenario::ConfigError (bad parameters or sim_config): the node exits with ROS_FATAL.
  SimulatorRos(ros::NodeHandle& nh, ros::NodeHandle& pnh);

  // Runs until shutdown: steps (unless paused), publishes, serves callbacks.
  void spin();

 private:
  void advance(int steps);
  // One autopilot exchange (px4 mode): false while the lock-step waits for the autopilot.
  bool exchangeWithAutopilot();
  void loadAutopilot(ros::NodeHandle& pnh, double physics_rate_hz);
  // Re-applies the last velocity command through the geofence (every publish tick).
  void applyVelocity();
  void waitForSubscribers();
  int subscribers(const std::string& topic) const;
  void publishState(bool force_ground_truth);
  void publishGroundTruth();
  void publishStaticFrames();
  void onVelocity(const geometry_msgs::Twist::ConstPtr& msg);
  void onPose(const geometry_msgs::PoseStamped::ConstPtr& msg);
  bool onStep(hameritt::StepSimulation::Request& req, hameritt::StepSimulation::Response& res);
  bool onPause(hameritt::SetPaused::Request& req, hameritt::SetPaused::Response& res);
  bool onReset(hameritt::ResetSimulation::Request& req, hameritt::ResetSimulation::Response& res);
  // Publishes ~end once the sim time has reached the duration.
  void publishEndOnce();

  // Declared first: the subscriptions and publishers below go through it.
  std::unique_ptr<LockstepGate> gate_;
  std::vector<std::string> lockstep_participants_;
  int steps_per_cycle_ = 10;
  scenario::SimConfig config_;
  std::unique_ptr<scenario::World> world_;
  std::unique_ptr<sim::Simulator> sim_;
  std::unique_ptr<CameraRig> cameras_;
  std::unique_ptr<sim::SetpointGuard> guard_;
  // internal | px4; the server when an external autopilot flies the UAV.
  std::string autopilot_ = "internal";
  std::unique_ptr<sitl::Px4Server> px4_;
  std::unique_ptr<sitl::ArduPilotServer> ardupilot_;
  std::unique_ptr<sitl::GcsTelemetry> gcs_;  // internal controller: telemetry for ground stations
  ros::Publisher autopilot_counters_pub_;
  ros::WallTime counters_published_;
  // The last accepted velocity command (valid while velocity_mode_).
  sim::Vec3 cmd_velocity_{0, 0, 0};
  double cmd_yaw_rate_ = 0.0;
  bool velocity_mode_ = false;
  double real_time_factor_ = 0.0;
  double duration_ = 0.0;
  std::vector<std::string> wait_for_;
  std::vector<std::string> wait_for_nodes_;
  double wait_timeout_ = 60.0;
  bool paused_ = false;
  bool crash_reported_ = false;
  int steps_per_publish_ = 1;
  int steps_per_ground_truth_ = 1;
  long long step_count_ = 0;

  ros::Publisher clock_pub_, odom_pub_, imu_pub_, truth_pub_, crash_pub_, tf_watch_,
      tf_static_watch_, end_pub_;
  // ~end (latched) announced for the duration reached (again after a reset).
  bool end_published_ = false;
  ros::Subscriber vel_sub_, pose_sub_;
  ros::ServiceServer step_srv_, pause_srv_, reset_srv_;
  tf2_ros::TransformBroadcaster tf_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
};

}  // namespace hameritt::ros_wrappers
