#include "hameritt/sitl/mavlink.h"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

namespace ml = hameritt::sitl::mavlink;

namespace {

std::uint16_t crcOf(const std::string& s, std::uint16_t crc = 0xFFFF) {
  return ml::crc16(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), crc);
}

struct Field {
  std::string type, name;
  int array = 0;
};

int sizeOf(const std::string& t) {
  if (t == "uint64_t" || t == "int64_t" || t == "double") return 8;
  if (t == "uint32_t" || t == "int32_t" || t == "float") return 4;
  if (t == "uint16_t" || t == "int16_t") return 2;
  return 1;
}

// mavgen's CRC_EXTRA: the CRC of "NAME " and, per base field in wire order (stable sort by type
// size, largest first), "type name " plus the array length byte; folded to 8 bits.
std::uint8_t crcExtraFromDefinition(const std::string& name, std::vector<Field> fields) {
  std::stable_sort(fields.begin(), fields.end(),
                   [](const Field& a, const Field& b) { return sizeOf(a.type) > sizeOf(b.type); });
  std::uint16_t crc = crcOf(name + " ");
  for (const auto& f : fields) {
    crc = crcOf(f.type + " ", crc);
    crc = crcOf(f.name + " ", crc);
    if (f.array) crc = ml::crcAccumulate(static_cast<std::uint8_t>(f.array), crc);
  }
  return static_cast<std::uint8_t>((crc & 0xFF) ^ (crc >> 8));
}

std::vector<Field> floats(std::initializer_list<const char*> names) {
  std::vector<Field> out;
  for (const char* n : names) out.push_back({"float", n});
  return out;
}

std::vector<Field> cat(std::vector<Field> a, const std::vector<Field>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace

TEST(MavlinkCrc, CheckValueOf123456789) {
  // CRC-16/MCRF4XX check value (the catalogue's "check" for 0x1021 reflected, init 0xFFFF).
  EXPECT_EQ(crcOf("123456789"), 0x6F91);
  // Negative control: one byte changed gives another CRC.
  EXPECT_NE(crcOf("123456780"), 0x6F91);
}

// The base fields of each message as common.xml declares them (declaration order).
TEST(MavlinkCrc, CrcExtraMatchesCommonXmlDefinitions) {
  const std::vector<std::pair<std::uint32_t, std::pair<std::string, std::vector<Field>>>> defs = {
      {ml::kHeartbeat,
       {"HEARTBEAT",
        {{"uint8_t", "type"},
         {"uint8_t", "autopilot"},
         {"uint8_t", "base_mode"},
         {"uint32_t", "custom_mode"},
         {"uint8_t", "system_status"},
         {"uint8_t", "mavlink_version"}}}},
      {ml::kSystemTime,
       {"SYSTEM_TIME", {{"uint64_t", "time_unix_usec"}, {"uint32_t", "time_boot_ms"}}}},
      {ml::kHilSensor,
       {"HIL_SENSOR",
        cat(cat({{"uint64_t", "time_usec"}},
                floats({"xacc", "yacc", "zacc", "xgyro", "ygyro", "zgyro", "xmag", "ymag", "zmag",
                        "abs_pressure", "diff_pressure", "pressure_alt", "temperature"})),
            {{"uint32_t", "fields_updated"}})}},
      {ml::kHilGps,
       {"HIL_GPS",
        {{"uint64_t", "time_usec"},
         {"uint8_t", "fix_type"},
         {"int32_t", "lat"},
         {"int32_t", "lon"},
         {"int32_t", "alt"},
         {"uint16_t", "eph"},
         {"uint16_t", "epv"},
         {"uint16_t", "vel"},
         {"int16_t", "vn"},
         {"int16_t", "ve"},
         {"int16_t", "vd"},
         {"uint16_t", "cog"},
         {"uint8_t", "satellites_visible"}}}},
      {ml::kHilStateQuaternion,
       {"HIL_STATE_QUATERNION",
        {{"uint64_t", "time_usec"},
         {"float", "attitude_quaternion", 4},
         {"float", "rollspeed"},
         {"float", "pitchspeed"},
         {"float", "yawspeed"},
         {"int32_t", "lat"},
         {"int32_t", "lon"},
         {"int32_t", "alt"},
         {"int16_t", "vx"},
         {"int16_t", "vy"},
         {"int16_t", "vz"},
         {"uint16_t", "ind_airspeed"},
         {"uint16_t", "true_airspeed"},
         {"int16_t", "xacc"},
         {"int16_t", "yacc"},
         {"int16_t", "zacc"}}}},
      {ml::kHilActuatorControls,
       {"HIL_ACTUATOR_CONTROLS",
        {{"uint64_t", "time_usec"},
         {"float", "controls", 16},
         {"uint8_t", "mode"},
         {"uint64_t", "flags"}}}},
      {ml::kCommandLong,
       {"COMMAND_LONG",
        cat({{"uint8_t", "target_system"},
             {"uint8_t", "target_component"},
             {"uint16_t", "command"},
             {"uint8_t", "confirmation"}},
            floats({"param1", "param2", "param3", "param4", "param5", "param6", "param7"}))}},
      {ml::kCommandAck, {"COMMAND_ACK", {{"uint16_t", "command"}, {"uint8_t", "result"}}}},
      {ml::kAttitude,
       {"ATTITUDE", cat({{"uint32_t", "time_boot_ms"}},
                        floats({"roll", "pitch", "yaw", "rollspeed", "pitchspeed", "yawspeed"}))}},
      {ml::kGlobalPositionInt,
       {"GLOBAL_POSITION_INT",
        {{"uint32_t", "time_boot_ms"},
         {"int32_t", "lat"},
         {"int32_t", "lon"},
         {"int32_t", "alt"},
         {"int32_t", "relative_alt"},
         {"int16_t", "vx"},
         {"int16_t", "vy"},
         {"int16_t", "vz"},
         {"uint16_t", "hdg"}}}},
  };
  for (const auto& [id, def] : defs) {
    const auto info = ml::messageInfo(id);
    ASSERT_TRUE(info) << def.first;
    EXPECT_EQ(info->crc_extra, crcExtraFromDefinition(def.first, def.second)) << def.first;
    int len = 0;
    for (const auto& f : def.second) len += sizeOf(f.type) * std::max(1, f.array);
    EXPECT_EQ(info->min_length, len) << def.first;
  }
  // The published values (MAVLink's generated headers), as a second reference.
  const std::vector<std::pair<std::uint32_t, int>> published = {
      {ml::kHeartbeat, 50},    {ml::kSystemTime, 137},       {ml::kHilSensor, 108},
      {ml::kHilGps, 124},      {ml::kHilStateQuaternion, 4}, {ml::kHilActuatorControls, 47},
      {ml::kCommandLong, 152}, {ml::kAttitude, 39},          {ml::kGlobalPositionInt, 104},
      {ml::kCommandAck, 143}};
  for (const auto& [id, extra] : published) EXPECT_EQ(ml::messageInfo(id)->crc_extra, extra) << id;
  // Negative control: a field renamed changes the extra.
  EXPECT_NE(crcExtraFromDefinition("HEARTBEAT", {{"uint8_t", "typ"}}), 50);
  EXPECT_FALSE(ml::messageInfo(12345));
}

TEST(MavlinkFrame, HeartbeatWorkedByHand) {
  // HEARTBEAT from system 1, component 1, seq 0: type 2 (quadrotor), autopilot 12 (PX4),
  // base_mode 0x81, custom_mode 0, system_status 4, mavlink_version 3. Payload in wire order:
  // custom_mode (u32) 00 00 00 00, then 02 0C 81 04 03. Header FD 09 00 00 00 01 01 00 00 00.
  // CRC-16/MCRF4XX over bytes 1..18 is 0x2B3A; with CRC_EXTRA 50 accumulated: 0x8C63, sent
  // little-endian 63 8C.
  ml::Heartbeat hb;
  hb.type = 2;
  hb.autopilot = 12;
  hb.base_mode = 0x81;
  hb.system_status = 4;
  const std::vector<std::uint8_t> expected = {0xFD, 0x09, 0x00, 0x00, 0x00, 0x01, 0x01,
                                              0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
                                              0x02, 0x0C, 0x81, 0x04, 0x03, 0x63, 0x8C};
  EXPECT_EQ(ml::encodeV2(ml::kHeartbeat, hb.pack(), 0, 1, 1), expected);
  const std::vector<std::uint8_t> header_payload(expected.begin() + 1, expected.end() - 2);
  EXPECT_EQ(ml::crc16(header_payload.data(), header_payload.size()), 0x2B3A);
  ml::Parser p;
  p.push(expected.data(), expected.size());
  const auto f = p.next();
  ASSERT_TRUE(f);
  const auto back = ml::Heartbeat::unpack(f->payload);
  EXPECT_EQ(back.autopilot, 12);
  EXPECT_EQ(back.base_mode, 0x81);
  EXPECT_EQ(f->sysid, 1);
}

TEST(MavlinkFrame, ZeroTruncationAndRoundTrip) {
  ml::HilActuatorControls a;
  a.time_usec = 4000;
  a.controls[0] = 0.5f;
  a.controls[3] = 0.25f;
  a.mode = 0;  // trailing zeros: mode and controls[4..15]
  const auto frame = ml::encodeV2(ml::kHilActuatorControls, a.pack(), 7, 1, 1);
  // Payload ends at controls[3]: 8 + 8 + 4 * 4 bytes.
  EXPECT_EQ(frame[1], 32);
  EXPECT_EQ(frame.size(), 32u + 12u);
  ml::Parser p;
  p.push(frame.data(), frame.size());
  const auto f = p.next();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->payload.size(), 81u);
  const auto b = ml::HilActuatorControls::unpack(f->payload);
  EXPECT_EQ(b.time_usec, 4000u);
  EXPECT_EQ(b.controls[0], 0.5f);
  EXPECT_EQ(b.controls[3], 0.25f);
  EXPECT_EQ(b.controls[15], 0.0f);
  EXPECT_EQ(f->seq, 7);
  // An all-zero payload keeps one byte.
  EXPECT_EQ(ml::encodeV2(ml::kCommandAck, ml::CommandAck().pack(), 0, 1, 1)[1], 1);

  ml::HilSensor s;
  s.time_usec = 123456789;
  s.zacc = -9.81f;
  s.abs_pressure = 1008.5f;
  s.fields_updated = ml::kUpdatedAccel | ml::kUpdatedGyro | ml::kUpdatedMag | ml::kUpdatedBaro;
  const auto sf = ml::encodeV2(ml::kHilSensor, s.pack(), 1, 1, 1);
  p.push(sf.data(), sf.size());
  const auto g = p.next();
  ASSERT_TRUE(g);
  const auto s2 = ml::HilSensor::unpack(g->payload);
  EXPECT_EQ(s2.time_usec, s.time_usec);
  EXPECT_EQ(s2.zacc, s.zacc);
  EXPECT_EQ(s2.abs_pressure, s.abs_pressure);
  EXPECT_EQ(s2.fields_updated, 0x1FFFu & ~0x400u);
}

TEST(MavlinkParser, ResynchronisesAfterStrayBytesAndRejectsBadCrc) {
  ml::SystemTime t;
  t.time_unix_usec = 42;
  t.time_boot_ms = 7;  // no truncation: a 24-byte frame
  const auto good = ml::encodeV2(ml::kSystemTime, t.pack(), 0, 1, 1);
  std::vector<std::uint8_t> stream = {0x00, 0x11, 0xFD, 0x22};  // a false start marker inside
  stream.insert(stream.end(), good.begin(), good.end());
  auto corrupted = good;
  corrupted[12] ^= 0x01;  // a payload bit flipped
  stream.insert(stream.end(), corrupted.begin(), corrupted.end());
  stream.insert(stream.end(), good.begin(), good.end());
  ml::Parser p;
  // Byte by byte: partial frames wait for the rest.
  int frames = 0;
  for (std::uint8_t b : stream) {
    p.push(&b, 1);
    while (auto f = p.next()) {
      EXPECT_EQ(ml::SystemTime::unpack(f->payload).time_unix_usec, 42u);
      ++frames;
    }
  }
  EXPECT_EQ(frames, 2);
  EXPECT_EQ(p.counters().frames, 2u);
  EXPECT_GE(p.counters().bad_crc, 1u);
  EXPECT_GE(p.counters().stray_bytes, 3u);
}

TEST(MavlinkParser, WrongCrcExtraRejected) {
  // A frame whose CRC was made with another message's CRC_EXTRA (a dialect mismatch).
  ml::Heartbeat hb;
  auto f = ml::encodeV2(ml::kHeartbeat, hb.pack(), 0, 1, 1);
  const std::size_t n = f.size();
  std::uint16_t crc = ml::crc16(f.data() + 1, n - 3);
  crc = ml::crcAccumulate(51, crc);  // not 50
  f[n - 2] = static_cast<std::uint8_t>(crc & 0xFF);
  f[n - 1] = static_cast<std::uint8_t>(crc >> 8);
  ml::Parser p;
  p.push(f.data(), f.size());
  EXPECT_FALSE(p.next());
  EXPECT_EQ(p.counters().bad_crc, 1u);
  // Control: with CRC_EXTRA 50 the same bytes are accepted.
  crc = ml::crcAccumulate(50, ml::crc16(f.data() + 1, n - 3));
  f[n - 2] = static_cast<std::uint8_t>(crc & 0xFF);
  f[n - 1] = static_cast<std::uint8_t>(crc >> 8);
  p.push(f.data(), f.size());
  EXPECT_TRUE(p.next());
}

TEST(MavlinkParser, ParsesV1Frames) {
  // v1: FE len seq sys comp msgid payload crc; CRC over len..payload plus CRC_EXTRA.
  ml::Heartbeat hb;
  hb.type = 6;
  hb.autopilot = 8;
  const auto payload = hb.pack();
  std::vector<std::uint8_t> f = {0xFE, 9, 3, 255, 190, 0};
  f.insert(f.end(), payload.begin(), payload.end());
  std::uint16_t crc = ml::crcAccumulate(50, ml::crc16(f.data() + 1, f.size() - 1));
  f.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  f.push_back(static_cast<std::uint8_t>(crc >> 8));
  ml::Parser p;
  p.push(f.data(), f.size());
  const auto got = p.next();
  ASSERT_TRUE(got);
  EXPECT_EQ(got->version, 1);
  EXPECT_EQ(got->sysid, 255);
  EXPECT_EQ(got->seq, 3);
  EXPECT_EQ(ml::Heartbeat::unpack(got->payload).type, 6);
  EXPECT_EQ(ml::Heartbeat::unpack(got->payload).autopilot, 8);
}

TEST(MavlinkParser, TruncatedFrameWaitsThenUnknownIdsCounted) {
  ml::Heartbeat hb;
  const auto f = ml::encodeV2(ml::kHeartbeat, hb.pack(), 0, 1, 1);
  ml::Parser p;
  p.push(f.data(), f.size() - 3);
  EXPECT_FALSE(p.next());
  EXPECT_EQ(p.pending(), f.size() - 3);
  // The rest never comes; a new frame follows: the truncated one fails its CRC, the new one is
  // found by resynchronisation.
  p.push(f.data(), f.size());
  int frames = 0;
  while (p.next()) ++frames;
  EXPECT_EQ(frames, 1);
  EXPECT_GE(p.counters().bad_crc + p.counters().stray_bytes, 1u);
  // Unknown message id 300: counted, skipped.
  std::vector<std::uint8_t> unk = {0xFD, 1, 0, 0, 0, 1, 1, 0x2C, 0x01, 0x00, 0x05, 0x00, 0x00};
  p.push(unk.data(), unk.size());
  EXPECT_FALSE(p.next());
  EXPECT_EQ(p.counters().unknown_id, 1u);
}
