#include "hameritt/sitl/ardupilot_server.h"

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "hameritt/scenario/error.h"
#include "hameritt/sitl/counters_json.h"

namespace hameritt::sitl {

namespace {

std::string num(double v) {
  char b[40];
  std::snprintf(b, sizeof(b), "%.9g", v);
  return b;
}

std::string vec(const Vec3& v) {
  return "[" + num(v.x()) + "," + num(v.y()) + "," + num(v.z()) + "]";
}

}  // namespace

std::string toJson(const ArduPilotCounters& c) {
  return countersJson({{"packets", c.packets},
                       {"bad_size", c.bad_size},
                       {"bad_magic", c.bad_magic},
                       {"duplicates", c.duplicates},
                       {"resets", c.resets},
                       {"missed_frames", c.missed_frames},
                       {"out_of_range_pwm", c.out_of_range_pwm},
                       {"stalls", c.stalls},
                       {"lockstep_steps", c.lockstep_steps},
                       {"state_messages", c.state_messages}});
}

std::string ardupilotStateJson(const sim::UavState& s, const ImuSample& imu) {
  const sim::Quat q = frdToNed(s.orientation);
  return "\n{\"timestamp\":" + num(s.t) + ",\"imu\":{\"gyro\":" + vec(imu.gyro) +
         ",\"accel_body\":" + vec(imu.accel) + "},\"position\":" + vec(enuToNed(s.position)) +
         ",\"velocity\":" + vec(enuToNed(s.velocity)) + ",\"quaternion\":[" + num(q.w()) + "," +
         num(q.x()) + "," + num(q.y()) + "," + num(q.z()) + "]}\n";
}

void ArduPilotConfig::validate(double physics_rate_hz) const {
  using scenario::ConfigError;
  if (port < 1 || instance < 0 || port + 10 * instance > 65535) {
    throw ConfigError("~ardupilot_port, ~instance: expected a port + 10 x instance in [1, 65535]");
  }
  const double steps = physics_rate_hz / sensor_rate_hz;
  if (!(sensor_rate_hz > 0 && steps >= 1 && std::abs(steps - std::round(steps)) < 1e-9)) {
    throw ConfigError("~sitl_sensor_rate_hz: expected a rate that divides physics_rate_hz, got " +
                      num(sensor_rate_hz));
  }
  if (!(stall_timeout_s > 0 && stall_timeout_s <= 3600)) {
    throw ConfigError("~sitl_timeout: expected (0, 3600] wall seconds, got " +
                      num(stall_timeout_s));
  }
}

ArduPilotServer::ArduPilotServer(const ArduPilotConfig& config, const SensorConfig& sensors,
                                 const sim::QuadrotorParams& uav, double physics_rate_hz, Log log)
    : config_(config), sensors_(sensors), log_(std::move(log)) {
  config_.validate(physics_rate_hz);
  max_speed_ = config_.max_rotor_speed > 0 ? config_.max_rotor_speed : uav.max_speed;
  steps_per_exchange_ = static_cast<int>(std::lround(physics_rate_hz / config_.sensor_rate_hz));
  port_ = config_.port + 10 * config_.instance;
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port_));
  const std::string where = config_.bind_address + ":" + std::to_string(port_);
  if (fd_ < 0 || ::inet_pton(AF_INET, config_.bind_address.c_str(), &addr.sin_addr) != 1 ||
      ::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    const std::string err = std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    throw std::runtime_error("ardupilot server: cannot bind UDP " + where + ": " + err);
  }
  if (log_) log_(LogLevel::kInfo, "ardupilot server: waiting for ArduPilot on UDP " + where);
}

ArduPilotServer::~ArduPilotServer() {
  if (fd_ >= 0) ::close(fd_);
}

void ArduPilotServer::logOnce(const std::string& kind, LogLevel level, const std::string& message) {
  if (logged_[kind]) return;
  logged_[kind] = true;
  if (log_) log_(level, message + " (logged once; counted in the server's counters)");
}

void ArduPilotServer::handle(const std::uint8_t* d, std::size_t n, const sockaddr_in& from) {
  if (n != 40) {
    ++counters_.bad_size;
    logOnce("size", LogLevel::kWarn, "ardupilot server: ignored a packet that is not 40 bytes");
    return;
  }
  std::uint16_t magic, rate, pwm[16];
  std::uint32_t frame;
  std::memcpy(&magic, d, 2);
  std::memcpy(&rate, d + 2, 2);
  std::memcpy(&frame, d + 4, 4);
  std::memcpy(pwm, d + 8, 32);
  if (magic != kServoMagic16) {
    ++counters_.bad_magic;
    logOnce("magic", LogLevel::kWarn, "ardupilot server: ignored a packet without magic 18458");
    return;
  }
  ++counters_.packets;
  peer_ = from;
  last_packet_wall_ = std::chrono::steady_clock::now();
  if (have_frame_ && frame == last_frame_) {
    ++counters_.duplicates;
    answer_again_ = true;  // ArduPilot resent: answer with the same state, no step
    return;
  }
  if (have_frame_ && frame < last_frame_) {
    ++counters_.resets;
    if (log_)
      log_(LogLevel::kWarn, "ardupilot server: frame count went back (ArduPilot restarted)");
  } else if (have_frame_ && frame > last_frame_ + 1) {
    counters_.missed_frames += frame - last_frame_ - 1;
    logOnce("gap", LogLevel::kWarn, "ardupilot server: frames missed");
  }
  have_frame_ = true;
  last_frame_ = frame;
  bool out_of_range = false;
  for (int i = 0; i < 4; ++i) {
    const double p = pwm[i];
    if (p < 1000 || p > 2000) out_of_range = true;
    controls_[i] = std::clamp((p - 1000.0) / 1000.0, 0.0, 1.0);
  }
  if (out_of_range) {
    ++counters_.out_of_range_pwm;
    logOnce("pwm", LogLevel::kWarn, "ardupilot server: motor PWM outside [1000, 2000] clamped");
  }
  last_packet_sim_time_ = sim_time_;
  if (!lockstep_) {
    lockstep_ = true;
    if (log_)
      log_(LogLevel::kInfo,
           "ardupilot server: lock-step with ArduPilot from sim " + num(sim_time_) + " s");
  }
  pending_ = true;
}

void ArduPilotServer::service(double wait_s) {
  pollfd p{fd_, POLLIN, 0};
  const int ms = static_cast<int>(std::ceil(std::max(0.0, wait_s) * 1000.0));
  if (::poll(&p, 1, ms) > 0) {
    for (;;) {
      std::uint8_t buf[512];
      sockaddr_in from{};
      socklen_t len = sizeof(from);
      const ssize_t n =
          ::recvfrom(fd_, buf, sizeof(buf), 0, reinterpret_cast<sockaddr*>(&from), &len);
      if (n < 0) break;
      handle(buf, static_cast<std::size_t>(n), from);
      if (pending_) break;  // one frame per step; the rest waits in the socket
    }
  }
  if (answer_again_ && !last_state_.empty()) {
    answer_again_ = false;
    ::sendto(fd_, last_state_.data(), last_state_.size(), 0,
             reinterpret_cast<const sockaddr*>(&peer_), sizeof(peer_));
    ++counters_.state_messages;
  }
  if (lockstep_ && !pending_ &&
      std::chrono::duration<double>(std::chrono::steady_clock::now() - last_packet_wall_).count() >
          config_.stall_timeout_s) {
    ++counters_.stalls;
    lockstep_ = false;
    have_frame_ = false;
    if (log_) {
      log_(LogLevel::kError, "ardupilot server: no servo packet for " +
                                 num(config_.stall_timeout_s) +
                                 " wall s in lock-step (~sitl_timeout); sim time stood at " +
                                 num(sim_time_) + " s; running on and waiting for ArduPilot");
    }
  }
}

void ArduPilotServer::applyMotors(sim::Simulator& sim) {
  if (lockstep_ && pending_) {
    pending_ = false;
    ++counters_.lockstep_steps;
  }
  const bool fresh = sim_time_ - last_packet_sim_time_ <= config_.actuator_timeout_s + 1e-9;
  Eigen::Vector4d w = Eigen::Vector4d::Zero();
  if (fresh) {
    for (int o = 0; o < 4; ++o)
      w[config_.layout[static_cast<std::size_t>(o)]] = controls_[o] * max_speed_;
  }
  sim.setRotorCommands(w);
}

void ArduPilotServer::sendState(const sim::UavState& s) {
  sim_time_ = s.t;
  if (!lockstep_) return;
  last_state_ = ardupilotStateJson(s, sensors_.imu(s));
  ::sendto(fd_, last_state_.data(), last_state_.size(), 0,
           reinterpret_cast<const sockaddr*>(&peer_), sizeof(peer_));
  ++counters_.state_messages;
}

}  // namespace hameritt::sitl
