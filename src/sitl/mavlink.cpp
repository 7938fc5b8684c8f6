#include "hameritt/sitl/mavlink.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

namespace hameritt::sitl::mavlink {

std::uint16_t crcAccumulate(std::uint8_t byte, std::uint16_t crc) {
  std::uint8_t tmp = static_cast<std::uint8_t>(byte ^ (crc & 0xFF));
  tmp = static_cast<std::uint8_t>(tmp ^ (tmp << 4));
  return static_cast<std::uint16_t>((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4));
}

std::uint16_t crc16(const std::uint8_t* data, std::size_t n, std::uint16_t crc) {
  for (std::size_t i = 0; i < n; ++i) crc = crcAccumulate(data[i], crc);
  return crc;
}

std::optional<MessageInfo> messageInfo(std::uint32_t id) {
  // CRC_EXTRA: the CRC of the message's name and base fields (common.xml), folded to 8 bits.
  switch (id) {
    case kHeartbeat:
      return MessageInfo{50, 9, 9};
    case kSystemTime:
      return MessageInfo{137, 12, 12};
    case kAttitude:
      return MessageInfo{39, 28, 28};
    case kGlobalPositionInt:
      return MessageInfo{104, 28, 28};
    case kCommandLong:
      return MessageInfo{152, 33, 33};
    case kCommandAck:
      return MessageInfo{143, 3, 10};
    case kHilActuatorControls:
      return MessageInfo{47, 81, 81};
    case kHilSensor:
      return MessageInfo{108, 64, 65};
    case kHilGps:
      return MessageInfo{124, 36, 39};
    case kHilStateQuaternion:
      return MessageInfo{4, 64, 64};
    default:
      return std::nullopt;
  }
}

std::vector<std::uint8_t> encodeV2(std::uint32_t msgid, const std::vector<std::uint8_t>& payload,
                                   std::uint8_t seq, std::uint8_t sysid, std::uint8_t compid) {
  const auto info = messageInfo(msgid);
  if (!info) throw std::invalid_argument("mavlink: unknown message id " + std::to_string(msgid));
  if (payload.size() > kMaxPayload) throw std::invalid_argument("mavlink: payload too long");
  // v2 drops trailing zero bytes of the payload (at least one byte stays).
  std::size_t len = payload.size();
  while (len > 1 && payload[len - 1] == 0) --len;
  std::vector<std::uint8_t> f;
  f.reserve(len + 12);
  f.push_back(kStxV2);
  f.push_back(static_cast<std::uint8_t>(len));
  f.push_back(0);  // incompat_flags
  f.push_back(0);  // compat_flags
  f.push_back(seq);
  f.push_back(sysid);
  f.push_back(compid);
  f.push_back(static_cast<std::uint8_t>(msgid & 0xFF));
  f.push_back(static_cast<std::uint8_t>((msgid >> 8) & 0xFF));
  f.push_back(static_cast<std::uint8_t>((msgid >> 16) & 0xFF));
  f.insert(f.end(), payload.begin(), payload.begin() + static_cast<std::ptrdiff_t>(len));
  std::uint16_t crc = crc16(f.data() + 1, f.size() - 1);
  crc = crcAccumulate(info->crc_extra, crc);
  f.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  f.push_back(static_cast<std::uint8_t>(crc >> 8));
  return f;
}

void Parser::push(const std::uint8_t* data, std::size_t n) {
  if (pos_ > 4096 && pos_ * 2 > buf_.size()) {
    buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(pos_));
    pos_ = 0;
  }
  buf_.insert(buf_.end(), data, data + n);
}

void Parser::dropPartial() {
  if (pos_ >= buf_.size()) return;
  ++counters_.truncated;
  ++pos_;
}

std::optional<Frame> Parser::next() {
  while (pos_ < buf_.size()) {
    const std::uint8_t stx = buf_[pos_];
    if (stx != kStxV2 && stx != kStxV1) {
      ++counters_.stray_bytes;
      ++pos_;
      continue;
    }
    const std::size_t avail = buf_.size() - pos_;
    const std::uint8_t* b = buf_.data() + pos_;
    const bool v2 = stx == kStxV2;
    const std::size_t header = v2 ? 10 : 6;
    if (avail < header) return std::nullopt;
    const std::size_t len = b[1];
    const bool is_signed = v2 && (b[2] & 0x01);
    const std::size_t total = header + len + 2 + (is_signed ? 13 : 0);
    if (avail < total) return std::nullopt;
    Frame f;
    f.version = v2 ? 2 : 1;
    if (v2) {
      f.seq = b[4];
      f.sysid = b[5];
      f.compid = b[6];
      f.msgid = static_cast<std::uint32_t>(b[7]) | (static_cast<std::uint32_t>(b[8]) << 8) |
                (static_cast<std::uint32_t>(b[9]) << 16);
    } else {
      f.seq = b[2];
      f.sysid = b[3];
      f.compid = b[4];
      f.msgid = b[5];
    }
    const auto info = messageInfo(f.msgid);
    if (!info) {
      // Unknown to us: its CRC cannot be checked. Skip only the marker, so that a start byte
      // inside garbage does not swallow a real frame behind it.
      ++counters_.unknown_id;
      ++pos_;
      continue;
    }
    std::uint16_t crc = crc16(b + 1, header - 1 + len);
    crc = crcAccumulate(info->crc_extra, crc);
    const std::uint16_t got =
        static_cast<std::uint16_t>(b[header + len] | (b[header + len + 1] << 8));
    if (crc != got) {
      ++counters_.bad_crc;
      ++pos_;
      continue;
    }
    if (len > info->max_length || (!v2 && len != info->min_length)) {
      ++counters_.bad_length;
      pos_ += total;
      continue;
    }
    if (is_signed) ++counters_.signed_frames;
    f.payload.assign(b + header, b + header + len);
    f.payload.resize(info->max_length, 0);  // v2 zero truncation undone
    pos_ += total;
    ++counters_.frames;
    return f;
  }
  buf_.clear();
  pos_ = 0;
  return std::nullopt;
}

// ------------------------------------------------------------------------ Writer / Reader

void Writer::raw(const void* p, std::size_t n) {
  if (at_ + n > buf_.size()) throw std::logic_error("mavlink::Writer: field beyond the payload");
  std::memcpy(buf_.data() + at_, p, n);  // little-endian hosts only (x86-64, arm64)
  at_ += n;
}
Writer& Writer::u8(std::uint8_t v) {
  raw(&v, 1);
  return *this;
}
Writer& Writer::u16(std::uint16_t v) {
  raw(&v, 2);
  return *this;
}
Writer& Writer::i16(std::int16_t v) {
  raw(&v, 2);
  return *this;
}
Writer& Writer::u32(std::uint32_t v) {
  raw(&v, 4);
  return *this;
}
Writer& Writer::i32(std::int32_t v) {
  raw(&v, 4);
  return *this;
}
Writer& Writer::u64(std::uint64_t v) {
  raw(&v, 8);
  return *this;
}
Writer& Writer::f32(float v) {
  raw(&v, 4);
  return *this;
}

void Reader::raw(void* p, std::size_t n) {
  // Short payloads read as zeros (the v2 truncation rule).
  std::memset(p, 0, n);
  if (at_ < buf_.size()) std::memcpy(p, buf_.data() + at_, std::min(n, buf_.size() - at_));
  at_ += n;
}
std::uint8_t Reader::u8() {
  std::uint8_t v;
  raw(&v, 1);
  return v;
}
std::uint16_t Reader::u16() {
  std::uint16_t v;
  raw(&v, 2);
  return v;
}
std::int16_t Reader::i16() {
  std::int16_t v;
  raw(&v, 2);
  return v;
}
std::uint32_t Reader::u32() {
  std::uint32_t v;
  raw(&v, 4);
  return v;
}
std::int32_t Reader::i32() {
  std::int32_t v;
  raw(&v, 4);
  return v;
}
std::uint64_t Reader::u64() {
  std::uint64_t v;
  raw(&v, 8);
  return v;
}
float Reader::f32() {
  float v;
  raw(&v, 4);
  return v;
}

// ------------------------------------------------------------------------------- Messages
// Wire order: fields sorted by type size, largest first (stable), extensions last.

std::vector<std::uint8_t> Heartbeat::pack() const {
  return Writer(9)
      .u32(custom_mode)
      .u8(type)
      .u8(autopilot)
      .u8(base_mode)
      .u8(system_status)
      .u8(mavlink_version)
      .take();
}
Heartbeat Heartbeat::unpack(const std::vector<std::uint8_t>& p) {
  Reader r(p);
  Heartbeat m;
  m.custom_mode = r.u32();
  m.type = r.u8();
  m.autopilot = r.u8();
  m.base_mode = r.u8();
  m.system_status = r.u8();
  m.mavlink_version = r.u8();
  return m;
}

std::vector<std::uint8_t> SystemTime::pack() const {
  return Writer(12).u64(time_unix_usec).u32(time_boot_ms).take();
}
SystemTime SystemTime::unpack(const std::vector<std::uint8_t>& p) {
  Reader r(p);
  SystemTime m;
  m.time_unix_usec = r.u64();
  m.time_boot_ms = r.u32();
  return m;
}

std::vector<std::uint8_t> HilSensor::pack() const {
  Writer w(65);
  w.u64(time_usec).f32(xacc).f32(yacc).f32(zacc).f32(xgyro).f32(ygyro).f32(zgyro);
  w.f32(xmag).f32(ymag).f32(zmag).f32(abs_pressure).f32(diff_pressure).f32(pressure_alt);
  w.f32(temperature).u32(fields_updated).u8(id);
  return w.take();
}
HilSensor HilSensor::unpack(const std::vector<std::uint8_t>& p) {
  Reader r(p);
  HilSensor m;
  m.time_usec = r.u64();
  for (float* f : {&m.xacc, &m.yacc, &m.zacc, &m.xgyro, &m.ygyro, &m.zgyro, &m.xmag, &m.ymag,
                   &m.zmag, &m.abs_pressure, &m.diff_pressure, &m.pressure_alt, &m.temperature}) {
    *f = r.f32();
  }
  m.fields_updated = r.u32();
  m.id = r.u8();
  return m;
}

std::vector<std::uint8_t> HilGps::pack() const {
  Writer w(39);
  w.u64(time_usec).i32(lat).i32(lon).i32(alt).u16(eph).u16(epv).u16(vel).i16(vn).i16(ve).i16(vd);
  w.u16(cog).u8(fix_type).u8(satellites_visible).u8(id).u16(yaw);
  return w.take();
}
HilGps HilGps::unpack(const std::vector<std::uint8_t>& p) {
  Reader r(p);
  HilGps m;
  m.time_usec = r.u64();
  m.lat = r.i32();
  m.lon = r.i32();
  m.alt = r.i32();
  m.eph = r.u16();
  m.epv = r.u16();
  m.vel = r.u16();
  m.vn = r.i16();
  m.ve = r.i16();
  m.vd = r.i16();
  m.cog = r.u16();
  m.fix_type = r.u8();
  m.satellites_visible = r.u8();
  m.id = r.u8();
  m.yaw = r.u16();
  return m;
}

std::vector<std::uint8_t> HilStateQuaternion::pack() const {
  Writer w(64);
  w.u64(time_usec);
  for (float q : attitude_quaternion) w.f32(q);
  w.f32(rollspeed).f32(pitchspeed).f32(yawspeed).i32(lat).i32(lon).i32(alt);
  w.i16(vx).i16(vy).i16(vz).u16(ind_airspeed).u16(true_airspeed).i16(xacc).i16(yacc).i16(zacc);
  return w.take();
}
HilStateQuaternion HilStateQuaternion::unpack(const std::vector<std::uint8_t>& p) {
  Reader r(p);
  HilStateQuaternion m;
  m.time_usec = r.u64();
  for (float& q : m.attitude_quaternion) q = r.f32();
  m.rollspeed = r.f32();
  m.pitchspeed = r.f32();
  m.yawspeed = r.f32();
  m.lat = r.i32();
  m.lon = r.i32();
  m.alt = r.i32();
  m.vx = r.i16();
  m.vy = r.i16();
  m.vz = r.i16();
  m.ind_airspeed = r.u16();
  m.true_airspeed = r.u16();
  m.xacc = r.i16();
  m.yacc = r.i16();
  m.zacc = r.i16();
  return m;
}

std::vector<std::uint8_t> HilActuatorControls::pack() const {
  Writer w(81);
  w.u64(time_usec).u64(flags);
  for (float c : controls) w.f32(c);
  w.u8(mode);
  return w.take();
}
HilActuatorControls HilActuatorControls::unpack(const std::vector<std::uint8_t>& p) {
  Reader r(p);
  HilActuatorControls m;
  m.time_usec = r.u64();
  m.flags = r.u64();
  for (float& c : m.controls) c = r.f32();
  m.mode = r.u8();
  return m;
}

std::vector<std::uint8_t> CommandLong::pack() const {
  Writer w(33);
  for (float v : param) w.f32(v);
  w.u16(command).u8(target_system).u8(target_component).u8(confirmation);
  return w.take();
}
CommandLong CommandLong::unpack(const std::vector<std::uint8_t>& p) {
  Reader r(p);
  CommandLong m;
  for (float& v : m.param) v = r.f32();
  m.command = r.u16();
  m.target_system = r.u8();
  m.target_component = r.u8();
  m.confirmation = r.u8();
  return m;
}

std::vector<std::uint8_t> CommandAck::pack() const {
  return Writer(3).u16(command).u8(result).take();
}
CommandAck CommandAck::unpack(const std::vector<std::uint8_t>& p) {
  Reader r(p);
  CommandAck m;
  m.command = r.u16();
  m.result = r.u8();
  return m;
}

std::vector<std::uint8_t> Attitude::pack() const {
  return Writer(28)
      .u32(time_boot_ms)
      .f32(roll)
      .f32(pitch)
      .f32(yaw)
      .f32(rollspeed)
      .f32(pitchspeed)
      .f32(yawspeed)
      .take();
}
Attitude Attitude::unpack(const std::vector<std::uint8_t>& p) {
  Reader r(p);
  Attitude m;
  m.time_boot_ms = r.u32();
  m.roll = r.f32();
  m.pitch = r.f32();
  m.yaw = r.f32();
  m.rollspeed = r.f32();
  m.pitchspeed = r.f32();
  m.yawspeed = r.f32();
  return m;
}

std::vector<std::uint8_t> GlobalPositionInt::pack() const {
  return Writer(28)
      .u32(time_boot_ms)
      .i32(lat)
      .i32(lon)
      .i32(alt)
      .i32(relative_alt)
      .i16(vx)
      .i16(vy)
      .i16(vz)
      .u16(hdg)
      .take();
}
GlobalPositionInt GlobalPositionInt::unpack(const std::vector<std::uint8_t>& p) {
  Reader r(p);
  GlobalPositionInt m;
  m.time_boot_ms = r.u32();
  m.lat = r.i32();
  m.lon = r.i32();
  m.alt = r.i32();
  m.relative_alt = r.i32();
  m.vx = r.i16();
  m.vy = r.i16();
  m.vz = r.i16();
  m.hdg = r.u16();
  return m;
}

}  // namespace hameritt::sitl::mavlink
