#pragma once
// Telemetry for ground stations (QGroundControl, MAVProxy) while the built-in controller flies:
// HEARTBEAT (1 Hz), ATTITUDE and GLOBAL_POSITION_INT (each at `rate_hz` of sim time) as MAVLink
// v2 over UDP to one address, 127.0.0.1:14550 by default (where QGroundControl listens).
// Send-only and ROS-free.

#include <netinet/in.h>

#include <cstdint>
#include <string>
#include <vector>

#include "hameritt/cop/geodetic.h"
#include "hameritt/sim/simulator.h"

namespace hameritt::sitl {

struct GcsConfig {
  std::string address = "127.0.0.1";
  int port = 14550;
  double rate_hz = 10.0;  // ATTITUDE and GLOBAL_POSITION_INT
  cop::Geodetic origin;   // the map frame's origin; altitude as MSL
  std::uint8_t sysid = 1;
  // Throws scenario::ConfigError naming the field ("~gcs_udp") and the value.
  void validate() const;
};

class GcsTelemetry {
 public:
  explicit GcsTelemetry(const GcsConfig& config);
  ~GcsTelemetry();
  GcsTelemetry(const GcsTelemetry&) = delete;
  GcsTelemetry& operator=(const GcsTelemetry&) = delete;
  // Sends what is due at the state's sim time; `armed` sets the heartbeat's armed flag.
  void update(const sim::UavState& s, bool armed);
  std::uint64_t messagesSent() const { return sent_; }

 private:
  void send(std::uint32_t msgid, const std::vector<std::uint8_t>& payload);
  GcsConfig config_;
  cop::EnuFrame frame_;
  int fd_ = -1;
  sockaddr_in to_{};
  std::uint8_t seq_ = 0;
  double next_heartbeat_ = 0, next_state_ = 0;
  std::uint64_t sent_ = 0;
};

}  // namespace hameritt::sitl
