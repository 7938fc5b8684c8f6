#pragma once
// A MAVLink codec for the messages of the simulator interfaces (PX4's simulator API and ground
// station telemetry): frame encoding and a resynchronising parser for MAVLink v2 (and v1 on
// input), CRC-16/MCRF4XX with each message's CRC_EXTRA, zero-truncated v2 payloads. The wire
// format and the message definitions are MAVLink's common.xml ("MAVLink Serialization",
// mavlink.io/en/guide/serialization.html). ROS-free and allocation-light.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace hameritt::sitl::mavlink {

inline constexpr std::uint8_t kStxV2 = 0xFD;
inline constexpr std::uint8_t kStxV1 = 0xFE;
inline constexpr std::size_t kMaxPayload = 255;

// CRC-16/MCRF4XX (the X.25 polynomial, initial value 0xFFFF, reflected, no final XOR).
std::uint16_t crcAccumulate(std::uint8_t byte, std::uint16_t crc);
std::uint16_t crc16(const std::uint8_t* data, std::size_t n, std::uint16_t crc = 0xFFFF);

// Message ids handled here.
enum MessageId : std::uint32_t {
  kHeartbeat = 0,
  kSystemTime = 2,
  kAttitude = 30,
  kGlobalPositionInt = 33,
  kCommandLong = 76,
  kCommandAck = 77,
  kHilActuatorControls = 93,
  kHilSensor = 107,
  kHilGps = 113,
  kHilStateQuaternion = 115,
};

// CRC_EXTRA and base payload length (without extension fields) of a known message; nullopt for
// an unknown id.
struct MessageInfo {
  std::uint8_t crc_extra;
  std::uint8_t min_length;  // base fields
  std::uint8_t max_length;  // with extensions
};
std::optional<MessageInfo> messageInfo(std::uint32_t id);

// One decoded frame: header fields and the payload zero-extended to the message's full length.
struct Frame {
  int version = 2;  // 1 or 2
  std::uint8_t seq = 0;
  std::uint8_t sysid = 0;
  std::uint8_t compid = 0;
  std::uint32_t msgid = 0;
  std::vector<std::uint8_t> payload;
};

// Encodes a MAVLink v2 frame (zero-truncated payload, no signing). `payload` is the full
// payload in wire order; throws std::invalid_argument for an unknown id or a too long payload.
std::vector<std::uint8_t> encodeV2(std::uint32_t msgid, const std::vector<std::uint8_t>& payload,
                                   std::uint8_t seq, std::uint8_t sysid, std::uint8_t compid);

// Counts of what the parser dropped, by kind.
struct ParserCounters {
  std::uint64_t frames = 0;         // accepted frames
  std::uint64_t stray_bytes = 0;    // bytes skipped while looking for a start marker
  std::uint64_t bad_crc = 0;        // checksum mismatch (corrupted bytes or a wrong CRC_EXTRA)
  std::uint64_t unknown_id = 0;     // well-formed frames of messages this codec does not know
  std::uint64_t bad_length = 0;     // a payload longer than the message's definition
  std::uint64_t signed_frames = 0;  // v2 frames with the signing flag (accepted, not verified)
  std::uint64_t truncated = 0;      // partial frames given up on (dropPartial)
};

// Incremental parser: push bytes as they arrive, take complete frames. After a bad frame it
// resynchronises on the next start marker after the bad frame's first byte.
class Parser {
 public:
  void push(const std::uint8_t* data, std::size_t n);
  // The next complete, valid frame, if any.
  std::optional<Frame> next();
  const ParserCounters& counters() const { return counters_; }
  // Bytes held while waiting for the rest of a frame.
  std::size_t pending() const { return buf_.size() - pos_; }
  // Gives up on the partial frame held (its sender stopped mid-frame): counts it as truncated
  // and rescans from the byte after its start marker.
  void dropPartial();

 private:
  std::vector<std::uint8_t> buf_;
  std::size_t pos_ = 0;
  ParserCounters counters_;
};

// Little-endian field writer / reader over a payload buffer.
class Writer {
 public:
  explicit Writer(std::size_t length) : buf_(length, 0) {}
  Writer& u8(std::uint8_t v);
  Writer& u16(std::uint16_t v);
  Writer& i16(std::int16_t v);
  Writer& u32(std::uint32_t v);
  Writer& i32(std::int32_t v);
  Writer& u64(std::uint64_t v);
  Writer& f32(float v);
  std::vector<std::uint8_t> take() { return std::move(buf_); }

 private:
  void raw(const void* p, std::size_t n);
  std::vector<std::uint8_t> buf_;
  std::size_t at_ = 0;
};

class Reader {
 public:
  explicit Reader(const std::vector<std::uint8_t>& buf) : buf_(buf) {}
  std::uint8_t u8();
  std::uint16_t u16();
  std::int16_t i16();
  std::uint32_t u32();
  std::int32_t i32();
  std::uint64_t u64();
  float f32();

 private:
  void raw(void* p, std::size_t n);
  const std::vector<std::uint8_t>& buf_;
  std::size_t at_ = 0;
};

// ---- Messages (fields in common.xml's units; pack() gives the full wire-order payload).

struct Heartbeat {
  std::uint32_t custom_mode = 0;
  std::uint8_t type = 2;           // MAV_TYPE_QUADROTOR
  std::uint8_t autopilot = 0;      // MAV_AUTOPILOT_GENERIC
  std::uint8_t base_mode = 0;      // MAV_MODE_FLAG_*
  std::uint8_t system_status = 4;  // MAV_STATE_ACTIVE
  std::uint8_t mavlink_version = 3;
  std::vector<std::uint8_t> pack() const;
  static Heartbeat unpack(const std::vector<std::uint8_t>& p);
};

struct SystemTime {
  std::uint64_t time_unix_usec = 0;
  std::uint32_t time_boot_ms = 0;
  std::vector<std::uint8_t> pack() const;
  static SystemTime unpack(const std::vector<std::uint8_t>& p);
};

// HIL_SENSOR fields_updated bits (HIL_SENSOR_UPDATED_FLAGS).
inline constexpr std::uint32_t kUpdatedAccel = 0x7;
inline constexpr std::uint32_t kUpdatedGyro = 0x38;
inline constexpr std::uint32_t kUpdatedMag = 0x1C0;
inline constexpr std::uint32_t kUpdatedBaro = 0x200 | 0x800 | 0x1000;  // abs, alt, temperature
inline constexpr std::uint32_t kUpdatedDiffPressure = 0x400;

struct HilSensor {
  std::uint64_t time_usec = 0;
  float xacc = 0, yacc = 0, zacc = 0;     // m/s^2, body FRD
  float xgyro = 0, ygyro = 0, zgyro = 0;  // rad/s, body FRD
  float xmag = 0, ymag = 0, zmag = 0;     // gauss, body FRD
  float abs_pressure = 0;                 // hPa
  float diff_pressure = 0;                // hPa
  float pressure_alt = 0;                 // m
  float temperature = 0;                  // degC
  std::uint32_t fields_updated = 0;
  std::uint8_t id = 0;  // extension
  std::vector<std::uint8_t> pack() const;
  static HilSensor unpack(const std::vector<std::uint8_t>& p);
};

struct HilGps {
  std::uint64_t time_usec = 0;
  std::int32_t lat = 0, lon = 0;             // degE7
  std::int32_t alt = 0;                      // mm (MSL)
  std::uint16_t eph = 0xFFFF, epv = 0xFFFF;  // HDOP/VDOP * 100
  std::uint16_t vel = 0xFFFF;                // cm/s ground speed
  std::int16_t vn = 0, ve = 0, vd = 0;       // cm/s NED
  std::uint16_t cog = 0xFFFF;                // cdeg
  std::uint8_t fix_type = 0;                 // 3: 3D fix
  std::uint8_t satellites_visible = 0xFF;
  std::uint8_t id = 0;    // extension
  std::uint16_t yaw = 0;  // extension, cdeg, 0: not available
  std::vector<std::uint8_t> pack() const;
  static HilGps unpack(const std::vector<std::uint8_t>& p);
};

struct HilStateQuaternion {
  std::uint64_t time_usec = 0;
  std::array<float, 4> attitude_quaternion{1, 0, 0, 0};  // w x y z, body FRD to NED
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;     // rad/s FRD
  std::int32_t lat = 0, lon = 0, alt = 0;                // degE7, degE7, mm
  std::int16_t vx = 0, vy = 0, vz = 0;                   // cm/s NED
  std::uint16_t ind_airspeed = 0, true_airspeed = 0;     // cm/s
  std::int16_t xacc = 0, yacc = 0, zacc = 0;             // mG
  std::vector<std::uint8_t> pack() const;
  static HilStateQuaternion unpack(const std::vector<std::uint8_t>& p);
};

// MAV_MODE_FLAG_SAFETY_ARMED in HIL_ACTUATOR_CONTROLS.mode; the lockstep flag in .flags.
inline constexpr std::uint8_t kModeFlagSafetyArmed = 128;
inline constexpr std::uint64_t kHilActuatorControlsLockstep = 1;

struct HilActuatorControls {
  std::uint64_t time_usec = 0;
  std::uint64_t flags = 0;
  std::array<float, 16> controls{};
  std::uint8_t mode = 0;
  std::vector<std::uint8_t> pack() const;
  static HilActuatorControls unpack(const std::vector<std::uint8_t>& p);
};

inline constexpr std::uint16_t kCmdSetMessageInterval = 511;

struct CommandLong {
  std::array<float, 7> param{};
  std::uint16_t command = 0;
  std::uint8_t target_system = 0, target_component = 0, confirmation = 0;
  std::vector<std::uint8_t> pack() const;
  static CommandLong unpack(const std::vector<std::uint8_t>& p);
};

struct CommandAck {
  std::uint16_t command = 0;
  std::uint8_t result = 0;  // MAV_RESULT
  std::vector<std::uint8_t> pack() const;
  static CommandAck unpack(const std::vector<std::uint8_t>& p);
};

struct Attitude {
  std::uint32_t time_boot_ms = 0;
  float roll = 0, pitch = 0, yaw = 0;  // rad, NED
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;
  std::vector<std::uint8_t> pack() const;
  static Attitude unpack(const std::vector<std::uint8_t>& p);
};

struct GlobalPositionInt {
  std::uint32_t time_boot_ms = 0;
  std::int32_t lat = 0, lon = 0, alt = 0, relative_alt = 0;  // degE7, mm
  std::int16_t vx = 0, vy = 0, vz = 0;                       // cm/s NED
  std::uint16_t hdg = 0xFFFF;                                // cdeg
  std::vector<std::uint8_t> pack() const;
  static GlobalPositionInt unpack(const std::vector<std::uint8_t>& p);
};

}  // namespace hameritt::sitl::mavlink
