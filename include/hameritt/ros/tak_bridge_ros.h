#pragma once
// The TAK bridge: sends the COP (cop/tracks), the UAV's own position (uav/odom) and the mission's
// areas of interest and keep-out zones (mission) as Cursor-on-Target events to TAK endpoints
// (UDP unicast/multicast, TCP or mutual TLS to a TAK server), as CoT XML or TAK Protocol
// Version 1. Sending happens on each endpoint's own thread
// (cop::TakSender): no ROS callback waits on the network.
//
// Topics (relative names): sub cop/tracks (hameritt/CopTrackArray), uav/odom (nav_msgs/Odometry,
// map frame), mission (hameritt/Mission, latched).
//
// Parameters (private): ~endpoints (comma-separated URLs, e.g. "udp://127.0.0.1:6969,
// tcp://10.0.0.5:8087,ssl://tak.example.org:8089"; "udp://" = multicast 239.2.3.1:6969, the
// default when unset), ~encoding (xml | protobuf), ~tls_client_p12, ~tls_client_cert,
// ~tls_client_key, ~tls_client_password, ~tls_trust_store, ~tls_trust_password,
// ~tls_pin_sha256, ~tls_server_name (cop::TakTlsConfig, ssl:// endpoints), ~rate_hz (1:
// UAV and tracks, wall time), ~zone_period_s (10), ~send_tentative (false: tentative tracks stay
// off TAK unless believed to be a target), ~origin_latitude, ~origin_longitude, ~origin_altitude
// (all three or none: overrides the mission's frame origin), ~uid_prefix, ~uav_callsign, ~stale_s,
// ~zone_stale_s, ~uav_ce, ~uav_le (cop::TakEventConfig), ~queue_capacity, ~multicast_ttl,
// ~reconnect_initial_s, ~reconnect_max_s, ~connect_timeout_s (cop::TakSenderConfig).
// config/tak.yaml holds the defaults (launch/cop.launch loads it).

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hameritt/CopTrackArray.h"
#include "hameritt/Mission.h"
#include "hameritt/cop/geodetic.h"
#include "hameritt/cop/tak_events.h"
#include "hameritt/cop/tak_sender.h"

namespace hameritt::ros_wrappers {

class TakBridgeRos {
 public:
  // Throws std::invalid_argument (cop::EndpointError, cop::GeodeticError) for bad parameters.
  TakBridgeRos(ros::NodeHandle& nh, ros::NodeHandle& pnh);

  // Events sent, dropped and failed per endpoint: the node's end-of-run summary.
  void logSummary() const;

 private:
  void onTracks(const hameritt::CopTrackArray::ConstPtr& msg);
  void onOdometry(const nav_msgs::Odometry::ConstPtr& msg);
  void onMission(const hameritt::Mission::ConstPtr& msg);
  void onTimer(const ros::WallTimerEvent&);
  void broadcast(const cop::CotEvent& event);
  void warnUnreachable();

  cop::TakEventConfig events_;
  std::vector<std::unique_ptr<cop::TakSender>> senders_;
  std::optional<cop::Geodetic> origin_override_;
  std::optional<cop::EnuFrame> frame_;
  std::vector<cop::ZoneReport> zones_;
  hameritt::CopTrackArray::ConstPtr tracks_;
  nav_msgs::Odometry::ConstPtr odom_;
  double zone_period_ = 10.0, last_zones_ = -1e18;
  bool send_tentative_ = false;
  std::uint64_t events_built_ = 0;

  ros::Subscriber tracks_sub_, odom_sub_, mission_sub_;
  ros::WallTimer timer_;
};

}  // namespace hameritt::ros_wrappers
