#include "hameritt/ros/tak_bridge_ros.h"

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "hameritt/cop/cot.h"
#include "hameritt/cop/tak_proto.h"
#include "hameritt/cop/tak_tls.h"
#include "hameritt/ros/cop_conversions.h"

namespace hameritt::ros_wrappers {
namespace {

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    const size_t a = item.find_first_not_of(" \t"), b = item.find_last_not_of(" \t");
    if (a != std::string::npos) out.push_back(item.substr(a, b - a + 1));
  }
  return out;
}

void requirePositive(double v, const char* name) {
  if (!std::isfinite(v) || v <= 0)
    throw std::invalid_argument(std::string("~") + name + " = " + std::to_string(v) +
                                " (expected > 0)");
}

}  // namespace

TakBridgeRos::TakBridgeRos(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  std::string endpoints;
  pnh.param<std::string>("endpoints", endpoints, "udp://");  // unset: TAK multicast
  const std::vector<std::string> urls = splitList(endpoints);
  if (urls.empty())
    throw std::invalid_argument(
        "~endpoints is empty (expected udp://A.B.C.D:PORT, "
        "tcp://A.B.C.D:PORT, ssl://HOST:PORT or udp:// for multicast, comma-separated)");
  double rate = 1.0;
  pnh.param("rate_hz", rate, rate);
  requirePositive(rate, "rate_hz");
  pnh.param("zone_period_s", zone_period_, zone_period_);
  requirePositive(zone_period_, "zone_period_s");
  pnh.param("send_tentative", send_tentative_, send_tentative_);
  pnh.param("uid_prefix", events_.uid_prefix, events_.uid_prefix);
  pnh.param("uav_callsign", events_.uav_callsign, events_.uav_callsign);
  pnh.param("stale_s", events_.stale_s, events_.stale_s);
  pnh.param("zone_stale_s", events_.zone_stale_s, events_.zone_stale_s);
  pnh.param("uav_ce", events_.uav_ce, events_.uav_ce);
  pnh.param("uav_le", events_.uav_le, events_.uav_le);
  events_.validate();

  const int origin_keys = pnh.hasParam("origin_latitude") + pnh.hasParam("origin_longitude") +
                          pnh.hasParam("origin_altitude");
  if (origin_keys != 0 && origin_keys != 3)
    throw std::invalid_argument(
        "~origin_latitude, ~origin_longitude, ~origin_altitude: set all "
        "three (an override of the mission's origin) or none");
  if (origin_keys == 3) {
    cop::Geodetic g;
    pnh.getParam("origin_latitude", g.latitude);
    pnh.getParam("origin_longitude", g.longitude);
    pnh.getParam("origin_altitude", g.altitude);
    cop::validateOrigin(g, "~origin_*");
    origin_override_ = g;
    frame_.emplace(g);
  }

  cop::TakSenderConfig sc;
  int capacity = static_cast<int>(sc.queue_capacity);
  pnh.param("queue_capacity", capacity, capacity);
  if (capacity < 1)
    throw std::invalid_argument("~queue_capacity = " + std::to_string(capacity) +
                                " (expected >= 1)");
  sc.queue_capacity = static_cast<std::size_t>(capacity);
  pnh.param("multicast_ttl", sc.multicast_ttl, sc.multicast_ttl);
  if (sc.multicast_ttl < 0 || sc.multicast_ttl > 255)
    throw std::invalid_argument("~multicast_ttl = " + std::to_string(sc.multicast_ttl) +
                                " (expected 0..255)");
  pnh.param("reconnect_initial_s", sc.reconnect_initial_s, sc.reconnect_initial_s);
  pnh.param("reconnect_max_s", sc.reconnect_max_s, sc.reconnect_max_s);
  pnh.param("connect_timeout_s", sc.connect_timeout_s, sc.connect_timeout_s);
  requirePositive(sc.reconnect_initial_s, "reconnect_initial_s");
  requirePositive(sc.reconnect_max_s, "reconnect_max_s");
  requirePositive(sc.connect_timeout_s, "connect_timeout_s");
  std::string encoding = "xml";
  pnh.param<std::string>("encoding", encoding, encoding);
  sc.encoding = cop::parseTakEncoding(encoding, "~encoding");
  pnh.param<std::string>("tls_client_p12", sc.tls.client_p12, "");
  pnh.param<std::string>("tls_client_cert", sc.tls.client_cert, "");
  pnh.param<std::string>("tls_client_key", sc.tls.client_key, "");
  pnh.param<std::string>("tls_client_password", sc.tls.client_password, "");
  pnh.param<std::string>("tls_trust_store", sc.tls.trust_store, "");
  pnh.param<std::string>("tls_trust_password", sc.tls.trust_password, "");
  pnh.param<std::string>("tls_pin_sha256", sc.tls.pin_sha256, "");
  pnh.param<std::string>("tls_server_name", sc.tls.server_name, "");
  sc.tls.validate();
  // The senders' threads log each failure once with its reason, and each connect.
  sc.log = [](bool error, const std::string& message) {
    if (error) {
      ROS_ERROR("tak_bridge: %s", message.c_str());
    } else {
      ROS_INFO("tak_bridge: %s", message.c_str());
    }
  };
  for (const std::string& url : urls) {
    senders_.push_back(std::make_unique<cop::TakSender>(cop::parseTakUrl(url), sc));
    if (senders_.back()->endpoint().protocol == cop::TakEndpoint::Protocol::kSsl &&
        !sc.tls.hasClientCertificate())
      ROS_WARN(
          "tak_bridge: %s without a client certificate (~tls_client_p12 or "
          "~tls_client_cert): a TAK Server's TLS input refuses the connection",
          url.c_str());
  }

  tracks_sub_ = nh.subscribe("cop/tracks", 5, &TakBridgeRos::onTracks, this);
  odom_sub_ = nh.subscribe("uav/odom", 5, &TakBridgeRos::onOdometry, this);
  mission_sub_ = nh.subscribe("mission", 1, &TakBridgeRos::onMission, this);
  timer_ = nh.createWallTimer(ros::WallDuration(1.0 / rate), &TakBridgeRos::onTimer, this);
  std::string names;
  for (const auto& s : senders_) names += (names.empty() ? "" : ", ") + s->endpoint().url();
  ROS_INFO("tak_bridge: CoT (%s) to %s at %.1f Hz, zones every %.0f s, origin %s", encoding.c_str(),
           names.c_str(), rate, zone_period_,
           origin_override_ ? "from ~origin_*" : "from the mission");
}

void TakBridgeRos::onTracks(const hameritt::CopTrackArray::ConstPtr& msg) { tracks_ = msg; }

void TakBridgeRos::onOdometry(const nav_msgs::Odometry::ConstPtr& msg) { odom_ = msg; }

void TakBridgeRos::onMission(const hameritt::Mission::ConstPtr& msg) {
  try {
    if (!origin_override_)
      frame_.emplace(
          cop::Geodetic{msg->origin_latitude, msg->origin_longitude, msg->origin_altitude});
    zones_ = zonesOf(*msg);
    last_zones_ = -1e18;  // send them at the next tick
    ROS_INFO("tak_bridge: mission %s: origin %.7f %.7f %.2f m, %zu zones", msg->scenario_id.c_str(),
             frame_->origin().latitude, frame_->origin().longitude, frame_->origin().altitude,
             zones_.size());
  } catch (const std::exception& e) {
    ROS_ERROR("tak_bridge: mission %s ignored: %s", msg->scenario_id.c_str(), e.what());
  }
}

void TakBridgeRos::broadcast(const cop::CotEvent& event) {
  events_built_++;
  for (const auto& s : senders_) s->send(event);
}

void TakBridgeRos::onTimer(const ros::WallTimerEvent&) {
  warnUnreachable();
  if (!frame_) {
    ROS_INFO_THROTTLE(10.0, "tak_bridge: waiting for the mission (geodetic origin)");
    return;
  }
  try {
    const double now = ros::WallTime::now().toSec();
    if (odom_) {
      const auto& p = odom_->pose.pose.position;
      const auto& v = odom_->twist.twist.linear;  // child frame: rotate into the map frame
      const auto& q = odom_->pose.pose.orientation;
      const Eigen::Quaterniond rot(q.w, q.x, q.y, q.z);
      const Eigen::Vector3d vel =
          (rot.norm() > 0.5 ? rot.normalized() : Eigen::Quaterniond::Identity()) *
          Eigen::Vector3d(v.x, v.y, v.z);
      broadcast(cop::uavEvent(*frame_, Eigen::Vector3d(p.x, p.y, p.z), vel, now, events_));
    }
    if (tracks_)
      for (const hameritt::CopTrack& t : tracks_->tracks)
        if (t.confirmed || send_tentative_ || !t.target_id.empty())
          broadcast(cop::trackEvent(*frame_, toTrackReport(t), now, events_));
    if (now - last_zones_ >= zone_period_) {
      last_zones_ = now;
      for (const cop::ZoneReport& z : zones_) broadcast(cop::zoneEvent(*frame_, z, now, events_));
    }
  } catch (const std::exception& e) {
    ROS_WARN_THROTTLE(5.0, "tak_bridge: event skipped: %s", e.what());
  }
}

void TakBridgeRos::warnUnreachable() {
  for (const auto& s : senders_) {
    const cop::TakSenderStats st = s->stats();
    if (st.connected || st.last_error.empty()) continue;
    // The reason itself was logged once when it first occurred.
    ROS_WARN_THROTTLE(30.0,
                      "tak_bridge: %s unreachable: %llu connect attempts (%llu TLS "
                      "failures), reconnect back-off %.1f s, %llu events dropped",
                      s->endpoint().url().c_str(),
                      static_cast<unsigned long long>(st.connect_attempts),
                      static_cast<unsigned long long>(st.tls_failures), st.next_backoff_s,
                      static_cast<unsigned long long>(st.dropped));
  }
}

void TakBridgeRos::logSummary() const {
  ROS_INFO("tak_bridge: summary: %llu events built",
           static_cast<unsigned long long>(events_built_));
  for (const auto& s : senders_) {
    const cop::TakSenderStats st = s->stats();
    const bool tcp = s->endpoint().stream();
    ROS_INFO("tak_bridge: summary: %s: %llu sent, %llu dropped, %llu send errors%s",
             s->endpoint().url().c_str(), static_cast<unsigned long long>(st.sent),
             static_cast<unsigned long long>(st.dropped),
             static_cast<unsigned long long>(st.send_errors),
             tcp ? (", " + std::to_string(st.connects) + " connects of " +
                    std::to_string(st.connect_attempts) + " attempts, " +
                    std::to_string(st.tls_failures) + " TLS failures")
                       .c_str()
                 : "");
  }
}

}  // namespace hameritt::ros_wrappers
