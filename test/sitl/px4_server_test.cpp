#include "hameritt/sitl/px4_server.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/world.h"
#include "sitl_test_util.h"
#include "hameritt/sim/quadrotor.h"

namespace hameritt::sitl {
namespace {

namespace ml = mavlink;

int testPort() { return 21000 + static_cast<int>(::getpid() % 20000); }

using test::calm;
using test::sentinel;

// A minimal autopilot side: a socket and the codec's parser.
struct Client {
  int fd = -1;
  ml::Parser parser;
  std::uint8_t seq = 0;
  explicit Client(int port) {
    fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  }
  ~Client() { close(); }
  void close() {
    if (fd >= 0) ::close(fd);
    fd = -1;
  }
  void sendRaw(const std::vector<std::uint8_t>& b) {
    ASSERT_EQ(::send(fd, b.data(), b.size(), MSG_NOSIGNAL), static_cast<ssize_t>(b.size()));
  }
  void send(std::uint32_t id, const std::vector<std::uint8_t>& p) {
    sendRaw(ml::encodeV2(id, p, seq++, 1, 1));
  }
  void actuators(double c, bool armed, std::uint64_t t_us) {
    ml::HilActuatorControls a;
    a.time_usec = t_us;
    for (int i = 0; i < 4; ++i) a.controls[static_cast<std::size_t>(i)] = static_cast<float>(c);
    a.mode = armed ? ml::kModeFlagSafetyArmed : 0;
    a.flags = ml::kHilActuatorControlsLockstep;
    send(ml::kHilActuatorControls, a.pack());
  }
  // Frames that arrived within `wait_s`.
  std::vector<ml::Frame> receive(double wait_s = 0.05) {
    std::vector<ml::Frame> out;
    pollfd p{fd, POLLIN, 0};
    while (::poll(&p, 1, static_cast<int>(wait_s * 1000)) > 0) {
      std::uint8_t buf[4096];
      const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
      if (n <= 0) break;
      parser.push(buf, static_cast<std::size_t>(n));
      while (auto f = parser.next()) out.push_back(*f);
      wait_s = 0.01;
    }
    return out;
  }
};

int count(const std::vector<ml::Frame>& fs, std::uint32_t id) {
  int n = 0;
  for (const auto& f : fs) n += f.msgid == id;
  return n;
}

struct Rig {
  scenario::World world;
  sim::Simulator sim;
  Px4Server server;
  explicit Rig(const Px4Config& pc, SensorConfig sc = SensorConfig())
      : sim(world, calm(), sentinel(), sim::SimSettings()),
        server(pc, sc, sentinel(), 500.0, nullptr) {}
  // One exchange if the server lets the simulation advance.
  bool exchange() {
    server.service(0.0);
    if (!server.readyToStep()) return false;
    server.applyMotors(sim);
    sim.step(server.stepsPerExchange());
    server.sendSensors(sim.uav());
    return true;
  }
};

Px4Config config() {
  Px4Config c;
  c.port = testPort();
  // Well above the gaps between the messages of the tests below on a loaded machine.
  c.stall_timeout_s = 1.0;
  c.silent_timeout_s = 1.0;
  return c;
}

TEST(Px4Server, FreeWheelsThenLocksStepToActuatorMessages) {
  Rig rig(config());
  Client client(rig.server.port());
  rig.server.service(0.1);
  ASSERT_TRUE(rig.server.connected());
  // Before the first actuator message: free-wheeling, at real time for a connected client.
  for (int i = 0; i < 5;) {
    if (rig.exchange())
      ++i;
    else
      rig.server.service(0.002);
  }
  auto frames = client.receive();
  EXPECT_EQ(count(frames, ml::kHilSensor), 5);
  EXPECT_EQ(count(frames, ml::kHeartbeat), 1);
  EXPECT_EQ(count(frames, ml::kSystemTime), 1);
  EXPECT_EQ(count(frames, ml::kHilGps), 1);
  EXPECT_EQ(count(frames, ml::kHilStateQuaternion), 0);  // not asked for
  std::uint64_t last = 0;
  for (const auto& f : frames) {
    if (f.msgid != ml::kHilSensor) continue;
    const auto s = ml::HilSensor::unpack(f.payload);
    EXPECT_EQ(s.time_usec, last + 4000);  // 250 Hz: one 4 ms period per message
    last = s.time_usec;
    EXPECT_EQ(s.fields_updated, 0x1BFFu);
    EXPECT_NEAR(s.zacc, -9.81, 0.3);
  }
  // Ask for HIL_STATE_QUATERNION every 4 ms.
  ml::CommandLong cmd;
  cmd.command = ml::kCmdSetMessageInterval;
  cmd.param[0] = ml::kHilStateQuaternion;
  cmd.param[1] = 4000;
  client.send(ml::kCommandLong, cmd.pack());
  // Lock-step: one exchange per actuator message; none -> sim time stands.
  client.actuators(0.0, true, last);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_TRUE(rig.exchange());
  EXPECT_TRUE(rig.server.lockstep());
  const double t = rig.sim.time();
  for (int i = 0; i < 20; ++i) EXPECT_FALSE(rig.exchange());
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_FALSE(rig.exchange());
  EXPECT_EQ(rig.sim.time(), t);
  frames = client.receive();
  EXPECT_EQ(count(frames, ml::kCommandAck), 1);
  EXPECT_EQ(count(frames, ml::kHilStateQuaternion), 1);
  for (int i = 0; i < 3; ++i) {
    client.actuators(0.0, true, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_TRUE(rig.exchange());
    EXPECT_FALSE(rig.exchange());
  }
  EXPECT_NEAR(rig.sim.time(), t + 3 * 0.004, 1e-12);
  EXPECT_EQ(rig.server.counters().lockstep_steps, 4u);
}

TEST(Px4Server, MotorsFromControlsZeroWhenDisarmed) {
  Rig rig(config());
  Client client(rig.server.port());
  rig.server.service(0.1);
  // One lock-step exchange per actuator message.
  auto step = [&](double c, bool armed) {
    client.actuators(c, armed, 0);
    for (;;) {
      rig.server.service(0.01);
      if (rig.server.lockstep() && rig.exchange()) return;
    }
  };
  const double hover = sentinel().hoverSpeed() / sentinel().max_speed;
  for (int i = 0; i < 50; ++i) step(0.9, false);  // disarmed: no thrust whatever the controls
  EXPECT_EQ(rig.sim.uav().rotor_speeds.norm(), 0.0);
  EXPECT_FALSE(rig.server.armed());
  for (int i = 0; i < 250; ++i) step(hover * 1.2, true);  // armed at 1.2 x hover: climbs
  EXPECT_TRUE(rig.server.armed());
  EXPECT_GT(rig.sim.uav().position.z(), 0.5);
  EXPECT_NEAR(rig.sim.uav().rotor_speeds[0], 1.2 * sentinel().hoverSpeed(), 1.0);
  // Out of range: clamped to full speed and counted.
  const double before = rig.sim.uav().rotor_speeds[0];
  step(1.5, true);
  EXPECT_EQ(rig.server.counters().out_of_range_actuators, 1u);
  EXPECT_GT(rig.sim.uav().rotor_speeds[0], before + 100);
  // NaN: ignored and counted; the lock-step still waits for a valid message.
  client.actuators(std::nan(""), true, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_FALSE(rig.exchange());
  EXPECT_EQ(rig.server.counters().nan_actuators, 1u);
  // No valid actuator message for over 0.2 s of sim time (the client went quiet in free-wheel
  // after a reconnect): the motors stop. Simulated here by dropping the client.
  client.close();
  rig.server.service(0.05);
  for (int i = 0; i < 200; ++i) ASSERT_TRUE(rig.exchange());
  EXPECT_LT(rig.sim.uav().rotor_speeds.norm(), 1.0);
}

TEST(Px4Server, StallTimesOutAndAcceptsReconnection) {
  Rig rig(config());
  {
    Client client(rig.server.port());
    rig.server.service(0.1);
    client.actuators(0.0, true, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ASSERT_TRUE(rig.exchange());
    const double t = rig.sim.time();
    // Stall: sim time stands until the timeout, then the client is dropped.
    const auto start = std::chrono::steady_clock::now();
    while (!rig.exchange() && std::chrono::steady_clock::now() - start < std::chrono::seconds(3)) {
      EXPECT_EQ(rig.sim.time(), t);
      rig.server.service(0.01);
    }
    EXPECT_EQ(rig.server.counters().stalls, 1u);
    EXPECT_FALSE(rig.server.connected());
    EXPECT_FALSE(rig.server.lockstep());
    for (int i = 0; i < 10; ++i) EXPECT_TRUE(rig.exchange());  // free-wheeling
  }
  Client again(rig.server.port());
  rig.server.service(0.1);
  EXPECT_TRUE(rig.server.connected());
  EXPECT_EQ(rig.server.counters().connections, 2u);
  // A second client while one is connected: refused and counted.
  Client third(rig.server.port());
  rig.server.service(0.1);
  EXPECT_EQ(rig.server.counters().refused_connections, 1u);
  // Disconnect: noticed, the simulation free-wheels.
  again.close();
  rig.server.service(0.1);
  EXPECT_FALSE(rig.server.connected());
  EXPECT_EQ(rig.server.counters().disconnects, 2u);
}

TEST(Px4Server, BadInputIgnoredAndCounted) {
  Rig rig(config());
  Client client(rig.server.port());
  rig.server.service(0.1);
  std::vector<std::uint8_t> sent = {0x01, 0x02, 0x03, 0x04, 0x05};  // garbage
  ml::Heartbeat hb;
  auto bad = ml::encodeV2(ml::kHeartbeat, hb.pack(), 0, 1, 1);
  bad.back() ^= 0xFF;  // bad CRC
  sent.insert(sent.end(), bad.begin(), bad.end());
  auto truncated = ml::encodeV2(ml::kHeartbeat, hb.pack(), 0, 1, 1);
  truncated.resize(6);
  sent.insert(sent.end(), truncated.begin(), truncated.end());
  const auto good = ml::encodeV2(ml::kHeartbeat, hb.pack(), 0, 1, 1);  // a good frame after it
  sent.insert(sent.end(), good.begin(), good.end());
  client.sendRaw(sent);
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(rig.exchange());
  // The server's counts are its parser's on the same bytes.
  ml::Parser replay;
  replay.push(sent.data(), sent.size());
  int frames = 0;
  while (replay.next()) ++frames;
  EXPECT_EQ(frames, 1);
  const Px4Counters& c = rig.server.counters();
  EXPECT_EQ(c.stray_bytes, replay.counters().stray_bytes);
  EXPECT_EQ(c.bad_crc, replay.counters().bad_crc);
  EXPECT_GE(c.stray_bytes, 5u);
  EXPECT_GE(c.bad_crc, 1u);
  EXPECT_TRUE(rig.server.connected());
  EXPECT_FALSE(rig.server.lockstep());
  EXPECT_NE(toJson(c).find("\"bad_crc\": "), std::string::npos);
}

TEST(Px4Server, SilentClientDropped) {
  Rig rig(config());
  Client client(rig.server.port());
  rig.server.service(0.1);
  ASSERT_TRUE(rig.server.connected());
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  rig.server.service(0.0);
  EXPECT_FALSE(rig.server.connected());
  EXPECT_EQ(rig.server.counters().silent_clients, 1u);
}

TEST(Px4Config, ValidationNamesTheField) {
  Px4Config c;
  c.sensor_rate_hz = 300;  // 500 / 300 is not whole
  EXPECT_THROW(c.validate(500), scenario::ConfigError);
  c = Px4Config();
  c.gps_rate_hz = 20;
  EXPECT_THROW(c.validate(500), scenario::ConfigError);
  c = Px4Config();
  c.port = 70000;
  EXPECT_THROW(c.validate(500), scenario::ConfigError);
  EXPECT_NO_THROW(Px4Config().validate(500));
  // The port in use: a clear error naming it.
  Px4Config a = config();
  Px4Server first(a, SensorConfig(), sentinel(), 500, nullptr);
  try {
    Px4Server second(a, SensorConfig(), sentinel(), 500, nullptr);
    FAIL() << "a second server bound the same port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(a.port)), std::string::npos);
  }
}

}  // namespace
}  // namespace hameritt::sitl
