#pragma once
// PX4's simulator API (the "simulator_mavlink" module's peer, as Gazebo and jMAVSim implement
// it): a TCP server on port 4560 + instance to which PX4 SITL connects. It sends HIL_SENSOR
// every sensor period, HIL_GPS at the GPS rate, SYSTEM_TIME and HEARTBEAT at 1 Hz and
// HIL_STATE_QUATERNION at the interval PX4 asks for with SET_MESSAGE_INTERVAL, and it turns
// HIL_ACTUATOR_CONTROLS into rotor speed commands. Lock-step: once the first actuator message
// came, the simulation advances one sensor period per actuator message; before that, and
// after the autopilot is gone, it runs freely. ROS-free; the wall clock is used only for the
// stall timeout.

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "hameritt/sim/quadrotor.h"
#include "hameritt/sim/simulator.h"
#include "hameritt/sitl/mavlink.h"
#include "hameritt/sitl/sensors.h"

namespace hameritt::sitl {

struct Px4Config {
  int port = 4560;  // + instance
  int instance = 0;
  std::string bind_address = "127.0.0.1";  // 0.0.0.0 for an autopilot on another host
  double sensor_rate_hz = 250.0;           // HIL_SENSOR rate = lock-step exchange rate
  double gps_rate_hz = 10.0;               // HIL_GPS, 5..10 Hz
  double stall_timeout_s = 5.0;            // wall seconds without an actuator message in lock-step
  double silent_timeout_s = 10.0;          // wall seconds a new client may stay silent
  double actuator_timeout_s = 0.2;         // sim seconds without actuators: motors stop
  sim::RotorLayout layout{0, 1, 2, 3};     // model rotor per motor output
  double max_rotor_speed = 0;              // rad/s for a control of 1 (0: the model's max_speed)
  // Throws scenario::ConfigError naming the field ("~px4_port") and the bad value.
  void validate(double physics_rate_hz) const;
};

// What the server ignored and why (each also logged once per kind).
struct Px4Counters {
  std::uint64_t connections = 0;
  std::uint64_t disconnects = 0;
  std::uint64_t refused_connections = 0;  // a second client while one is connected
  std::uint64_t stalls = 0;               // lock-step timeouts (the client was dropped)
  std::uint64_t silent_clients = 0;       // connected and said nothing (dropped)
  std::uint64_t overflows = 0;            // a client that stopped reading (dropped)
  std::uint64_t stray_bytes = 0, bad_crc = 0, unknown_messages = 0, bad_length = 0;
  std::uint64_t truncated = 0;               // a partial frame not completed within 0.1 s
  std::uint64_t nan_actuators = 0;           // messages with a non-finite motor control (ignored)
  std::uint64_t out_of_range_actuators = 0;  // motor controls outside [0, 1] (clamped)
  std::uint64_t actuator_messages = 0;
  std::uint64_t lockstep_steps = 0;
  std::uint64_t sensor_messages = 0, gps_messages = 0, state_messages = 0;
};

// The counters as one JSON object (the node publishes it on ~autopilot_counters).
std::string toJson(const Px4Counters& c);

class Px4Server {
 public:
  enum class LogLevel { kInfo, kWarn, kError };
  using Log = std::function<void(LogLevel, const std::string&)>;

  // Binds and listens; throws std::runtime_error naming the address and port when it cannot.
  Px4Server(const Px4Config& config, const SensorConfig& sensors, const sim::QuadrotorParams& uav,
            double physics_rate_hz, Log log);
  ~Px4Server();
  Px4Server(const Px4Server&) = delete;
  Px4Server& operator=(const Px4Server&) = delete;

  // Accepts, reads and writes without blocking longer than `wait_s` wall seconds; drops a
  // stalled, silent or overflowing client.
  void service(double wait_s);
  // True when the next sensor period may be simulated: without a client (free-wheeling); with
  // a client before its first actuator message, at real time since it connected; in lock-step,
  // once an actuator message answered the last HIL_SENSOR.
  bool readyToStep() const;
  // Physics steps per sensor period.
  int stepsPerExchange() const { return steps_per_exchange_; }
  // Consumes the pending actuator message (lock-step) and sets the rotor commands: the last
  // actuator message's, or zero when disarmed or none came for actuator_timeout_s sim seconds.
  void applyMotors(sim::Simulator& sim);
  // After the sensor period is simulated: HIL_SENSOR and what else is due, stamped sim time.
  void sendSensors(const sim::UavState& s);

  bool connected() const;
  bool lockstep() const { return lockstep_; }
  bool armed() const { return armed_; }
  int port() const { return port_; }
  const Px4Counters& counters() const { return counters_; }

 private:
  void accept();
  void readClient();
  void flush();
  void drop(const std::string& why);
  void handle(const mavlink::Frame& f);
  void send(std::uint32_t msgid, const std::vector<std::uint8_t>& payload);
  void logOnce(const std::string& kind, LogLevel level, const std::string& message);
  void syncParserCounters();

  Px4Config config_;
  SensorModel sensors_;
  double max_speed_;
  double dt_exchange_;
  int steps_per_exchange_ = 1;
  Log log_;
  int listen_fd_ = -1;
  int client_fd_ = -1;
  int port_ = 0;
  std::unique_ptr<mavlink::Parser> parser_;
  mavlink::ParserCounters parser_seen_;
  std::vector<std::uint8_t> outbox_;
  std::uint8_t seq_ = 0;
  bool lockstep_ = false;
  bool heard_ = false;  // the client has sent a valid frame
  int pending_actuators_ = 0;
  bool armed_ = false;
  Eigen::Vector4d controls_{0, 0, 0, 0};
  double last_actuator_sim_time_ = -1e9;
  double sim_time_ = 0;
  double connect_sim_time_ = 0;
  std::chrono::steady_clock::time_point connected_at_, last_actuator_wall_, last_bytes_wall_;
  std::int64_t state_interval_us_ = -1;  // HIL_STATE_QUATERNION off until asked for
  double next_gps_ = 0, next_state_ = 0, next_heartbeat_ = 0;
  std::map<std::string, bool> logged_;
  Px4Counters counters_;
};

}  // namespace hameritt::sitl
