#include "hameritt/sitl/gcs_telemetry.h"

#include <arpa/inet.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hameritt/scenario/error.h"
#include "hameritt/sitl/mavlink.h"
#include "hameritt/sitl/sensors.h"

namespace hameritt::sitl {

namespace ml = mavlink;

void GcsConfig::validate() const {
  in_addr a{};
  if (::inet_pton(AF_INET, address.c_str(), &a) != 1 || port < 1 || port > 65535) {
    throw scenario::ConfigError("~gcs_udp: expected IPV4:PORT, got " + address + ":" +
                                std::to_string(port));
  }
  if (!(rate_hz > 0 && rate_hz <= 100)) {
    throw scenario::ConfigError("~gcs_rate_hz: expected (0, 100] Hz, got " +
                                std::to_string(rate_hz));
  }
}

GcsTelemetry::GcsTelemetry(const GcsConfig& config) : config_(config), frame_(config.origin) {
  config_.validate();
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error("gcs telemetry: cannot open a UDP socket");
  to_.sin_family = AF_INET;
  to_.sin_port = htons(static_cast<std::uint16_t>(config_.port));
  ::inet_pton(AF_INET, config_.address.c_str(), &to_.sin_addr);
}

GcsTelemetry::~GcsTelemetry() {
  if (fd_ >= 0) ::close(fd_);
}

void GcsTelemetry::send(std::uint32_t msgid, const std::vector<std::uint8_t>& payload) {
  const auto f = ml::encodeV2(msgid, payload, seq_++, config_.sysid, 1);
  // Fire and forget: nobody listening is not an error.
  if (::sendto(fd_, f.data(), f.size(), 0, reinterpret_cast<const sockaddr*>(&to_), sizeof(to_)) ==
      static_cast<ssize_t>(f.size())) {
    ++sent_;
  }
}

void GcsTelemetry::update(const sim::UavState& s, bool armed) {
  const double eps = 1e-9;
  const auto boot_ms = static_cast<std::uint32_t>(std::llround(s.t * 1000.0));
  if (s.t + eps >= next_heartbeat_) {
    next_heartbeat_ = s.t + 1.0;
    ml::Heartbeat hb;
    hb.type = 2;                                                      // MAV_TYPE_QUADROTOR
    hb.autopilot = 0;                                                 // MAV_AUTOPILOT_GENERIC
    hb.base_mode = static_cast<std::uint8_t>(8 | (armed ? 128 : 0));  // guided (+ armed)
    hb.system_status = armed ? 4 : 3;                                 // active : standby
    send(ml::kHeartbeat, hb.pack());
  }
  if (s.t + eps < next_state_) return;
  next_state_ = s.t + 1.0 / config_.rate_hz;
  const sim::Quat q = frdToNed(s.orientation);
  const Eigen::Matrix3d r = q.toRotationMatrix();
  ml::Attitude a;
  a.time_boot_ms = boot_ms;
  a.roll = static_cast<float>(std::atan2(r(2, 1), r(2, 2)));
  a.pitch = static_cast<float>(std::asin(std::clamp(-r(2, 0), -1.0, 1.0)));
  a.yaw = static_cast<float>(std::atan2(r(1, 0), r(0, 0)));
  const Vec3 w = fluToFrd(s.angular_velocity);
  a.rollspeed = static_cast<float>(w.x());
  a.pitchspeed = static_cast<float>(w.y());
  a.yawspeed = static_cast<float>(w.z());
  send(ml::kAttitude, a.pack());
  const cop::Geodetic g = frame_.toGeodetic(s.position);
  ml::GlobalPositionInt p;
  p.time_boot_ms = boot_ms;
  p.lat = static_cast<std::int32_t>(std::llround(g.latitude * 1e7));
  p.lon = static_cast<std::int32_t>(std::llround(g.longitude * 1e7));
  p.alt = static_cast<std::int32_t>(std::llround(g.altitude * 1000.0));
  p.relative_alt = static_cast<std::int32_t>(std::llround(s.position.z() * 1000.0));
  const Vec3 v = enuToNed(s.velocity);
  p.vx = static_cast<std::int16_t>(std::lround(std::clamp(v.x() * 100, -32767.0, 32767.0)));
  p.vy = static_cast<std::int16_t>(std::lround(std::clamp(v.y() * 100, -32767.0, 32767.0)));
  p.vz = static_cast<std::int16_t>(std::lround(std::clamp(v.z() * 100, -32767.0, 32767.0)));
  double hdg = a.yaw * 180.0 / M_PI;
  if (hdg < 0) hdg += 360.0;
  p.hdg = static_cast<std::uint16_t>(std::lround(hdg * 100.0) % 36000);
  send(ml::kGlobalPositionInt, p.pack());
}

}  // namespace hameritt::sitl
