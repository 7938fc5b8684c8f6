#pragma once
// ArduPilot's SITL JSON interface (libraries/SITL/SIM_JSON): ArduPilot sends a 40-byte servo
// packet per frame over UDP (uint16 magic 18458, uint16 frame_rate, uint32 frame_count,
// 16 x uint16 PWM, little-endian) to port 9002 + 10 x instance; the simulator answers each new
// frame with one JSON line of the vehicle state (timestamp, IMU, NED position, velocity,
// attitude quaternion). Lock-step: from the first packet on, one sensor period per new frame;
// a repeated frame count is answered again without a step (a duplicate), a smaller one is
// ArduPilot restarting (a reset), a larger jump is counted as missed frames. ROS-free.

#include <netinet/in.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "hameritt/sim/quadrotor.h"
#include "hameritt/sim/simulator.h"
#include "hameritt/sitl/sensors.h"

namespace hameritt::sitl {

inline constexpr std::uint16_t kServoMagic16 = 18458;

struct ArduPilotConfig {
  int port = 9002;  // + 10 x instance
  int instance = 0;
  std::string bind_address = "127.0.0.1";
  double sensor_rate_hz = 250.0;        // one exchange per new frame: this much sim time
  double stall_timeout_s = 5.0;         // wall seconds without a frame in lock-step
  double actuator_timeout_s = 0.2;      // sim seconds without frames: motors stop
  sim::RotorLayout layout{0, 1, 2, 3};  // ArduPilot's quad-X order is PX4's
  double max_rotor_speed = 0;           // rad/s at PWM 2000 (0: the model's max_speed)
  void validate(double physics_rate_hz) const;
};

struct ArduPilotCounters {
  std::uint64_t packets = 0;   // valid servo packets
  std::uint64_t bad_size = 0;  // not 40 bytes
  std::uint64_t bad_magic = 0;
  std::uint64_t duplicates = 0;        // the same frame count again (answered, no step)
  std::uint64_t resets = 0;            // a smaller frame count (ArduPilot restarted)
  std::uint64_t missed_frames = 0;     // frame counts skipped
  std::uint64_t out_of_range_pwm = 0;  // motor PWM outside [1000, 2000] (clamped)
  std::uint64_t stalls = 0;            // lock-step timeouts (the autopilot was forgotten)
  std::uint64_t lockstep_steps = 0;
  std::uint64_t state_messages = 0;  // JSON lines sent
};

std::string toJson(const ArduPilotCounters& c);

// The JSON line for a state (also used by the tests): NED position relative to the map origin,
// FRD IMU from the sensor model.
std::string ardupilotStateJson(const sim::UavState& s, const ImuSample& imu);

class ArduPilotServer {
 public:
  enum class LogLevel { kInfo, kWarn, kError };
  using Log = std::function<void(LogLevel, const std::string&)>;

  ArduPilotServer(const ArduPilotConfig& config, const SensorConfig& sensors,
                  const sim::QuadrotorParams& uav, double physics_rate_hz, Log log);
  ~ArduPilotServer();
  ArduPilotServer(const ArduPilotServer&) = delete;
  ArduPilotServer& operator=(const ArduPilotServer&) = delete;

  void service(double wait_s);
  bool readyToStep() const { return !lockstep_ || pending_; }
  int stepsPerExchange() const { return steps_per_exchange_; }
  void applyMotors(sim::Simulator& sim);
  // After the step: the JSON line answering the frame (nothing while free-wheeling).
  void sendState(const sim::UavState& s);
  bool lockstep() const { return lockstep_; }
  int port() const { return port_; }
  const ArduPilotCounters& counters() const { return counters_; }

 private:
  void handle(const std::uint8_t* data, std::size_t n, const sockaddr_in& from);
  void reply(const sim::UavState& s);
  void logOnce(const std::string& kind, LogLevel level, const std::string& message);

  ArduPilotConfig config_;
  SensorModel sensors_;
  double max_speed_;
  int steps_per_exchange_ = 1;
  Log log_;
  int fd_ = -1;
  int port_ = 0;
  sockaddr_in peer_{};
  bool lockstep_ = false;
  bool pending_ = false;
  bool answer_again_ = false;  // a duplicate frame waits for the last state again
  bool have_frame_ = false;
  std::uint32_t last_frame_ = 0;
  Eigen::Vector4d controls_{0, 0, 0, 0};
  double last_packet_sim_time_ = -1e9;
  double sim_time_ = 0;
  std::chrono::steady_clock::time_point last_packet_wall_;
  std::string last_state_;
  std::map<std::string, bool> logged_;
  ArduPilotCounters counters_;
};

}  // namespace hameritt::sitl
