#include "hameritt/sitl/px4_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "hameritt/scenario/error.h"
#include "hameritt/sitl/counters_json.h"

namespace hameritt::sitl {

namespace ml = mavlink;

namespace {

constexpr std::uint8_t kSysId = 1;
constexpr std::uint8_t kCompId = 51;         // MAV_COMP_ID_USER27: the simulator
constexpr std::size_t kMaxOutbox = 1 << 20;  // bytes queued for a client that does not read

std::int32_t degE7(double deg) { return static_cast<std::int32_t>(std::llround(deg * 1e7)); }
std::int16_t cm16(double m) {
  return static_cast<std::int16_t>(std::clamp(std::lround(m * 100.0), -32767L, 32767L));
}

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%g", v);
  return b;
}

}  // namespace

std::string toJson(const Px4Counters& c) {
  return countersJson({{"connections", c.connections},
                       {"disconnects", c.disconnects},
                       {"refused_connections", c.refused_connections},
                       {"stalls", c.stalls},
                       {"silent_clients", c.silent_clients},
                       {"overflows", c.overflows},
                       {"stray_bytes", c.stray_bytes},
                       {"bad_crc", c.bad_crc},
                       {"unknown_messages", c.unknown_messages},
                       {"bad_length", c.bad_length},
                       {"truncated", c.truncated},
                       {"nan_actuators", c.nan_actuators},
                       {"out_of_range_actuators", c.out_of_range_actuators},
                       {"actuator_messages", c.actuator_messages},
                       {"lockstep_steps", c.lockstep_steps},
                       {"sensor_messages", c.sensor_messages},
                       {"gps_messages", c.gps_messages},
                       {"state_messages", c.state_messages}});
}

void Px4Config::validate(double physics_rate_hz) const {
  using scenario::ConfigError;
  if (port < 1 || port > 65535 || instance < 0 || port + instance > 65535) {
    throw ConfigError("~px4_port, ~instance: expected a port + instance in [1, 65535], got " +
                      std::to_string(port) + " + " + std::to_string(instance));
  }
  const double steps = physics_rate_hz / sensor_rate_hz;
  if (!(sensor_rate_hz > 0 && steps >= 1 && std::abs(steps - std::round(steps)) < 1e-9)) {
    throw ConfigError("~sitl_sensor_rate_hz: expected a rate that divides physics_rate_hz (" +
                      num(physics_rate_hz) + ") into whole steps, got " + num(sensor_rate_hz));
  }
  if (!(gps_rate_hz >= 5 && gps_rate_hz <= 10)) {
    throw ConfigError("~sitl_gps_rate_hz: expected 5..10 Hz, got " + num(gps_rate_hz));
  }
  if (!(stall_timeout_s > 0 && stall_timeout_s <= 3600)) {
    throw ConfigError("~sitl_timeout: expected (0, 3600] wall seconds, got " +
                      num(stall_timeout_s));
  }
  if (!(silent_timeout_s > 0 && silent_timeout_s <= 3600)) {
    throw ConfigError("~sitl_silent_timeout: expected (0, 3600] wall seconds, got " +
                      num(silent_timeout_s));
  }
  if (!(actuator_timeout_s > 0)) {
    throw ConfigError("~sitl_actuator_timeout: expected > 0 s, got " + num(actuator_timeout_s));
  }
  if (!(max_rotor_speed >= 0 && std::isfinite(max_rotor_speed))) {
    throw ConfigError("~sitl_max_rotor_speed: expected >= 0 rad/s, got " + num(max_rotor_speed));
  }
}

Px4Server::Px4Server(const Px4Config& config, const SensorConfig& sensors,
                     const sim::QuadrotorParams& uav, double physics_rate_hz, Log log)
    : config_(config), sensors_(sensors), log_(std::move(log)) {
  config_.validate(physics_rate_hz);
  max_speed_ = config_.max_rotor_speed > 0 ? config_.max_rotor_speed : uav.max_speed;
  steps_per_exchange_ = static_cast<int>(std::lround(physics_rate_hz / config_.sensor_rate_hz));
  dt_exchange_ = steps_per_exchange_ / physics_rate_hz;
  port_ = config_.port + config_.instance;
  const std::string where = config_.bind_address + ":" + std::to_string(port_);
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0)
    throw std::runtime_error("px4 server: socket(): " + std::string(std::strerror(errno)));
  const int one = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port_));
  if (::inet_pton(AF_INET, config_.bind_address.c_str(), &addr.sin_addr) != 1) {
    ::close(listen_fd_);
    throw scenario::ConfigError("~sitl_bind_address: expected an IPv4 address, got " +
                                config_.bind_address);
  }
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
      ::listen(listen_fd_, 4) != 0) {
    const std::string err = std::strerror(errno);
    ::close(listen_fd_);
    throw std::runtime_error("px4 server: cannot listen on " + where + ": " + err +
                             " (another simulator instance? use another ~instance)");
  }
  if (log_) log_(LogLevel::kInfo, "px4 server: waiting for PX4 on TCP " + where);
}

Px4Server::~Px4Server() {
  if (client_fd_ >= 0) ::close(client_fd_);
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

bool Px4Server::connected() const { return client_fd_ >= 0; }

bool Px4Server::readyToStep() const {
  if (lockstep_) return pending_actuators_ > 0;
  if (client_fd_ < 0) return true;
  // A client that has not locked step yet (an autopilot booting) is served in real time, so
  // that no backlog of sensor messages builds up in its socket: every sensor message still in
  // flight when the lock-step starts would stay a step of latency for the whole flight.
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - connected_at_).count();
  return sim_time_ - connect_sim_time_ <= wall;
}

void Px4Server::logOnce(const std::string& kind, LogLevel level, const std::string& message) {
  if (logged_[kind]) return;
  logged_[kind] = true;
  if (log_) log_(level, message + " (logged once; counted in the server's counters)");
}

void Px4Server::drop(const std::string& why) {
  if (client_fd_ < 0) return;
  ::close(client_fd_);
  client_fd_ = -1;
  outbox_.clear();
  parser_.reset();
  lockstep_ = false;
  heard_ = false;
  pending_actuators_ = 0;
  ++counters_.disconnects;
  if (log_) {
    log_(LogLevel::kError, "px4 server: client dropped: " + why +
                               "; the simulation runs freely and accepts a new connection");
  }
}

void Px4Server::accept() {
  for (;;) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;
    if (client_fd_ >= 0) {
      ::close(fd);
      ++counters_.refused_connections;
      logOnce("refused", LogLevel::kWarn,
              "px4 server: a second client connected while one is active; refused");
      continue;
    }
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    client_fd_ = fd;
    parser_ = std::make_unique<ml::Parser>();
    parser_seen_ = ml::ParserCounters();
    heard_ = false;
    lockstep_ = false;
    pending_actuators_ = 0;
    connected_at_ = std::chrono::steady_clock::now();
    connect_sim_time_ = sim_time_;
    last_actuator_wall_ = last_bytes_wall_ = connected_at_;
    next_heartbeat_ = next_gps_ = next_state_ = sim_time_;
    state_interval_us_ = -1;
    ++counters_.connections;
    if (log_)
      log_(LogLevel::kInfo, "px4 server: client connected on port " + std::to_string(port_));
  }
}

void Px4Server::syncParserCounters() {
  if (!parser_) return;
  const ml::ParserCounters& c = parser_->counters();
  auto add = [&](std::uint64_t now, std::uint64_t& seen, std::uint64_t& total, const char* kind,
                 const char* what) {
    if (now > seen) {
      total += now - seen;
      seen = now;
      logOnce(kind, LogLevel::kWarn, std::string("px4 server: ignored ") + what);
    }
  };
  add(c.stray_bytes, parser_seen_.stray_bytes, counters_.stray_bytes, "stray",
      "bytes outside MAVLink frames");
  add(c.bad_crc, parser_seen_.bad_crc, counters_.bad_crc, "crc", "a frame with a bad checksum");
  add(c.unknown_id, parser_seen_.unknown_id, counters_.unknown_messages, "unknown",
      "a frame of a message this simulator does not handle");
  add(c.bad_length, parser_seen_.bad_length, counters_.bad_length, "length",
      "a frame longer than its message");
  add(c.truncated, parser_seen_.truncated, counters_.truncated, "truncated",
      "a frame cut short (no more bytes within 0.1 s)");
}

void Px4Server::readClient() {
  std::uint8_t buf[8192];
  for (;;) {
    const ssize_t n = ::recv(client_fd_, buf, sizeof(buf), 0);
    if (n > 0) {
      last_bytes_wall_ = std::chrono::steady_clock::now();
      parser_->push(buf, static_cast<std::size_t>(n));
      while (client_fd_ >= 0) {
        auto f = parser_->next();
        if (!f) break;
        handle(*f);
      }
      syncParserCounters();
      if (client_fd_ < 0) return;
      continue;
    }
    if (n == 0) {
      drop("the autopilot closed the connection");
      return;
    }
    if (errno == EAGAIN || errno == EWOULDBLOCK) return;
    if (errno == EINTR) continue;
    drop(std::string("read error: ") + std::strerror(errno));
    return;
  }
}

void Px4Server::handle(const ml::Frame& f) {
  heard_ = true;
  switch (f.msgid) {
    case ml::kHilActuatorControls: {
      const auto a = ml::HilActuatorControls::unpack(f.payload);
      bool finite = true, in_range = true;
      for (int i = 0; i < 4; ++i) {
        const float c = a.controls[static_cast<std::size_t>(i)];
        if (!std::isfinite(c))
          finite = false;
        else if (c < 0.0f || c > 1.0f)
          in_range = false;
      }
      if (!finite) {
        ++counters_.nan_actuators;
        logOnce("nan", LogLevel::kWarn,
                "px4 server: HIL_ACTUATOR_CONTROLS with a non-finite motor control ignored");
        return;
      }
      if (!in_range) {
        ++counters_.out_of_range_actuators;
        logOnce("range", LogLevel::kWarn,
                "px4 server: HIL_ACTUATOR_CONTROLS motor control outside [0, 1] clamped");
      }
      for (int i = 0; i < 4; ++i) {
        controls_[i] =
            std::clamp(static_cast<double>(a.controls[static_cast<std::size_t>(i)]), 0.0, 1.0);
      }
      armed_ = (a.mode & ml::kModeFlagSafetyArmed) != 0;
      last_actuator_sim_time_ = sim_time_;
      last_actuator_wall_ = std::chrono::steady_clock::now();
      ++counters_.actuator_messages;
      if (!lockstep_) {
        lockstep_ = true;
        if (log_)
          log_(LogLevel::kInfo,
               "px4 server: lock-step with the autopilot from sim " + num(sim_time_) + " s");
      }
      ++pending_actuators_;
      break;
    }
    case ml::kCommandLong: {
      const auto c = ml::CommandLong::unpack(f.payload);
      ml::CommandAck ack;
      ack.command = c.command;
      if (c.command == ml::kCmdSetMessageInterval &&
          static_cast<std::uint32_t>(c.param[0]) == ml::kHilStateQuaternion) {
        const double us = c.param[1];
        state_interval_us_ = us < 0 ? -1 : (us == 0 ? 20000 : static_cast<std::int64_t>(us));
        next_state_ = sim_time_;
        ack.result = 0;  // MAV_RESULT_ACCEPTED
      } else {
        ack.result = 3;  // MAV_RESULT_UNSUPPORTED
      }
      send(ml::kCommandAck, ack.pack());
      break;
    }
    default:
      break;  // HEARTBEAT and the rest: no action needed
  }
}

void Px4Server::send(std::uint32_t msgid, const std::vector<std::uint8_t>& payload) {
  if (client_fd_ < 0) return;
  const auto frame = ml::encodeV2(msgid, payload, seq_++, kSysId, kCompId);
  outbox_.insert(outbox_.end(), frame.begin(), frame.end());
}

void Px4Server::flush() {
  while (client_fd_ >= 0 && !outbox_.empty()) {
    const ssize_t n = ::send(client_fd_, outbox_.data(), outbox_.size(), MSG_NOSIGNAL);
    if (n > 0) {
      outbox_.erase(outbox_.begin(), outbox_.begin() + n);
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
    if (n < 0 && errno == EINTR) continue;
    drop(std::string("write error: ") + std::strerror(errno));
    return;
  }
  if (outbox_.size() > kMaxOutbox) {
    ++counters_.overflows;
    drop("it stopped reading (over 1 MiB queued)");
  }
}

void Px4Server::service(double wait_s) {
  pollfd fds[2];
  fds[0] = {listen_fd_, POLLIN, 0};
  int n = 1;
  if (client_fd_ >= 0) {
    fds[1] = {client_fd_, static_cast<short>(POLLIN | (outbox_.empty() ? 0 : POLLOUT)), 0};
    n = 2;
  }
  const int ms = static_cast<int>(std::ceil(std::max(0.0, wait_s) * 1000.0));
  if (::poll(fds, static_cast<nfds_t>(n), ms) > 0) {
    if (fds[0].revents & POLLIN) accept();
    if (n == 2 && client_fd_ >= 0 && (fds[1].revents & (POLLIN | POLLHUP | POLLERR))) readClient();
  }
  flush();
  if (client_fd_ < 0) return;
  const auto now = std::chrono::steady_clock::now();
  const auto seconds = [&](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(now - t).count();
  };
  // A frame cut short: give up on it after 0.1 s without bytes, so that a lock-step waiting
  // for the frames behind it does not stall.
  while (client_fd_ >= 0 && parser_ && parser_->pending() > 0 && seconds(last_bytes_wall_) > 0.1) {
    parser_->dropPartial();
    while (client_fd_ >= 0) {
      auto f = parser_->next();
      if (!f) break;
      handle(*f);
    }
    syncParserCounters();
  }
  if (client_fd_ < 0) return;
  if (!heard_ && seconds(connected_at_) > config_.silent_timeout_s) {
    ++counters_.silent_clients;
    drop("no valid MAVLink frame in " + num(config_.silent_timeout_s) +
         " s (~sitl_silent_timeout)");
  } else if (lockstep_ && pending_actuators_ == 0 &&
             seconds(last_actuator_wall_) > config_.stall_timeout_s) {
    ++counters_.stalls;
    drop("no HIL_ACTUATOR_CONTROLS for " + num(config_.stall_timeout_s) +
         " wall s in lock-step (~sitl_timeout); sim time stood at " + num(sim_time_) + " s");
  }
}

void Px4Server::applyMotors(sim::Simulator& sim) {
  if (lockstep_ && pending_actuators_ > 0) {
    --pending_actuators_;
    ++counters_.lockstep_steps;
  }
  const bool fresh = sim_time_ - last_actuator_sim_time_ <= config_.actuator_timeout_s + 1e-9;
  Eigen::Vector4d w = Eigen::Vector4d::Zero();
  if (armed_ && fresh) {
    for (int o = 0; o < 4; ++o) {
      w[config_.layout[static_cast<std::size_t>(o)]] = controls_[o] * max_speed_;
    }
  }
  sim.setRotorCommands(w);
}

void Px4Server::sendSensors(const sim::UavState& s) {
  sim_time_ = s.t;
  if (client_fd_ < 0) return;
  const auto t_us = static_cast<std::uint64_t>(std::llround(s.t * 1e6));
  const double eps = 1e-9;
  if (s.t + eps >= next_heartbeat_) {
    next_heartbeat_ = s.t + 1.0;
    ml::Heartbeat hb;
    hb.type = 2;       // quadrotor
    hb.autopilot = 8;  // MAV_AUTOPILOT_INVALID: not a flight controller
    hb.system_status = 4;
    send(ml::kHeartbeat, hb.pack());
    ml::SystemTime st;
    st.time_unix_usec =
        static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                       std::chrono::system_clock::now().time_since_epoch())
                                       .count());
    st.time_boot_ms = static_cast<std::uint32_t>(t_us / 1000);
    send(ml::kSystemTime, st.pack());
  }
  const ImuSample imu = sensors_.imu(s);
  const Vec3 mag = sensors_.mag(s);
  const BaroSample baro = sensors_.baro(s);
  ml::HilSensor hs;
  hs.time_usec = t_us;
  hs.xacc = static_cast<float>(imu.accel.x());
  hs.yacc = static_cast<float>(imu.accel.y());
  hs.zacc = static_cast<float>(imu.accel.z());
  hs.xgyro = static_cast<float>(imu.gyro.x());
  hs.ygyro = static_cast<float>(imu.gyro.y());
  hs.zgyro = static_cast<float>(imu.gyro.z());
  hs.xmag = static_cast<float>(mag.x());
  hs.ymag = static_cast<float>(mag.y());
  hs.zmag = static_cast<float>(mag.z());
  hs.abs_pressure = static_cast<float>(baro.pressure_hpa);
  hs.pressure_alt = static_cast<float>(baro.altitude_m);
  hs.temperature = static_cast<float>(baro.temperature_c);
  hs.fields_updated = ml::kUpdatedAccel | ml::kUpdatedGyro | ml::kUpdatedMag | ml::kUpdatedBaro;
  send(ml::kHilSensor, hs.pack());
  ++counters_.sensor_messages;
  if (s.t + eps >= next_gps_) {
    next_gps_ = s.t + 1.0 / config_.gps_rate_hz;
    const GpsSample g = sensors_.gps(s);
    ml::HilGps m;
    m.time_usec = t_us;
    m.fix_type = 3;
    m.lat = degE7(g.position.latitude);
    m.lon = degE7(g.position.longitude);
    m.alt = static_cast<std::int32_t>(std::lround(g.position.altitude * 1000.0));
    m.eph = static_cast<std::uint16_t>(std::lround(g.eph * 100.0));
    m.epv = static_cast<std::uint16_t>(std::lround(g.epv * 100.0));
    const double ground = g.velocity_ned.head<2>().norm();
    m.vel = static_cast<std::uint16_t>(std::lround(ground * 100.0));
    m.vn = cm16(g.velocity_ned.x());
    m.ve = cm16(g.velocity_ned.y());
    m.vd = cm16(g.velocity_ned.z());
    double cog = std::atan2(g.velocity_ned.y(), g.velocity_ned.x()) * 180.0 / M_PI;
    if (cog < 0) cog += 360.0;
    m.cog = static_cast<std::uint16_t>(std::lround(cog * 100.0) % 36000);
    m.satellites_visible = 12;
    send(ml::kHilGps, m.pack());
    ++counters_.gps_messages;
  }
  if (state_interval_us_ > 0 && s.t + eps >= next_state_) {
    next_state_ = s.t + state_interval_us_ * 1e-6;
    ml::HilStateQuaternion q;
    q.time_usec = t_us;
    const sim::Quat a = frdToNed(s.orientation);
    q.attitude_quaternion = {static_cast<float>(a.w()), static_cast<float>(a.x()),
                             static_cast<float>(a.y()), static_cast<float>(a.z())};
    const Vec3 w = fluToFrd(s.angular_velocity);
    q.rollspeed = static_cast<float>(w.x());
    q.pitchspeed = static_cast<float>(w.y());
    q.yawspeed = static_cast<float>(w.z());
    const cop::Geodetic g = sensors_.geodetic(s.position);
    q.lat = degE7(g.latitude);
    q.lon = degE7(g.longitude);
    q.alt = static_cast<std::int32_t>(std::lround(g.altitude * 1000.0));
    const Vec3 v = enuToNed(s.velocity);
    q.vx = cm16(v.x());
    q.vy = cm16(v.y());
    q.vz = cm16(v.z());
    const Vec3 acc = fluToFrd(s.specific_force) / 9.80665 * 1000.0;  // mG
    q.xacc = static_cast<std::int16_t>(std::clamp(std::lround(acc.x()), -32767L, 32767L));
    q.yacc = static_cast<std::int16_t>(std::clamp(std::lround(acc.y()), -32767L, 32767L));
    q.zacc = static_cast<std::int16_t>(std::clamp(std::lround(acc.z()), -32767L, 32767L));
    send(ml::kHilStateQuaternion, q.pack());
    ++counters_.state_messages;
  }
  flush();
}

}  // namespace hameritt::sitl
