#pragma once
// The Common Operational Picture node: fuses the perception clients' claims and the ADK's
// perfect-perception reports into tracks (cop::OperationalPicture) and publishes them.
//
// Topics (relative names): sub perception/detections (hameritt/Detection), adk/perfect_perception
// (hameritt/PerceptionReport), mission (hameritt/Mission, latched: the targets); pub cop/tracks
// (hameritt/CopTrackArray, every live track at ~publish_rate_hz) and cop/markers
// (visualization_msgs/MarkerArray).
//
// Parameters (private): ~publish_rate_hz (2), ~frame_id ("map"), ~claim_sigma (3 m),
// ~perfect_sigma (0.5 m), and cop::CopConfig's fields: ~process_accel_sigma, ~height_walk_sigma,
// ~gate_chi2, ~merge_chi2, ~initial_speed_sigma, ~confirm_hits, ~tentative_timeout,
// ~confirmed_timeout, ~belief_threshold.

#include <ros/ros.h>

#include <string>

#include "hameritt/Detection.h"
#include "hameritt/Mission.h"
#include "hameritt/PerceptionReport.h"
#include "hameritt/cop/operational_picture.h"

namespace hameritt::ros_wrappers {

// Serves callbacks until SIGINT or SIGTERM (or ros::shutdown), leaving rosconsole up so that the
// node can log its summary afterwards; call after ros::init(..., NoSigintHandler).
void spinUntilSignal();

class CopRos {
 public:
  // Throws std::invalid_argument for bad parameters (the node exits with ROS_FATAL).
  CopRos(ros::NodeHandle& nh, ros::NodeHandle& pnh);

  // One line per believed target and the counters: the node's end-of-run summary.
  void logSummary() const;

 private:
  void onDetection(const hameritt::Detection::ConstPtr& msg);
  void onPerception(const hameritt::PerceptionReport::ConstPtr& msg);
  void onMission(const hameritt::Mission::ConstPtr& msg);
  void onTimer(const ros::TimerEvent&);
  void publish(const ros::Time& now);

  cop::OperationalPicture picture_;
  std::string frame_id_ = "map";
  double claim_sigma_ = 3.0, perfect_sigma_ = 0.5;
  std::uint64_t reports_ = 0, publications_ = 0;

  ros::Subscriber detection_sub_, perception_sub_, mission_sub_;
  ros::Publisher tracks_pub_, markers_pub_;
  ros::Timer timer_;
};

}  // namespace hameritt::ros_wrappers
