#include "hameritt/sitl/ardupilot_server.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <string>
#include <thread>

#include "hameritt/scenario/world.h"
#include "sitl_test_util.h"

namespace hameritt::sitl {
namespace {

using test::calm;
using test::sentinel;

std::vector<std::uint8_t> packet(std::uint32_t frame, std::uint16_t pwm,
                                 std::uint16_t magic = kServoMagic16) {
  std::vector<std::uint8_t> b(40, 0);
  const std::uint16_t rate = 250;
  std::memcpy(b.data(), &magic, 2);
  std::memcpy(b.data() + 2, &rate, 2);
  std::memcpy(b.data() + 4, &frame, 4);
  for (int i = 0; i < 16; ++i) std::memcpy(b.data() + 8 + 2 * i, &pwm, 2);
  return b;
}

struct Rig {
  scenario::World world;
  sim::Simulator sim;
  ArduPilotServer server;
  int fd;
  sockaddr_in to{};
  explicit Rig(int port)
      : sim(world, calm(), sentinel(), sim::SimSettings()),
        server(
            [&] {
              ArduPilotConfig c;
              c.port = port;
              c.stall_timeout_s = 1.0;  // well above the gaps between the packets below
              return c;
            }(),
            SensorConfig(), sentinel(), 500.0, nullptr) {
    fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<std::uint16_t>(server.port()));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  }
  ~Rig() { ::close(fd); }
  void send(const std::vector<std::uint8_t>& b) {
    ::sendto(fd, b.data(), b.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof(to));
  }
  // Services until a step is due (or 0.2 s pass), then steps; returns whether it stepped.
  bool exchange() {
    for (int i = 0; i < 100; ++i) {
      server.service(0.002);
      if (server.lockstep() && server.readyToStep()) {
        server.applyMotors(sim);
        sim.step(server.stepsPerExchange());
        server.sendState(sim.uav());
        return true;
      }
    }
    return false;
  }
  std::string receive() {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 200) <= 0) return "";
    char buf[2048];
    const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : "";
  }
};

TEST(ArduPilotServer, FrameCountsAndJsonLines) {
  Rig rig(23000 + static_cast<int>(::getpid() % 20000));
  // Free-wheeling before the first packet: no lock-step, no reply.
  EXPECT_FALSE(rig.server.lockstep());
  rig.send(packet(0, 1000));
  ASSERT_TRUE(rig.exchange());
  const std::string first = rig.receive();
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(first.front(), '\n');
  EXPECT_EQ(first.back(), '\n');
  EXPECT_NE(first.find("\"timestamp\":0.004,"), std::string::npos) << first;
  EXPECT_NE(first.find("\"accel_body\":["), std::string::npos);
  // A duplicate: the same line again, no step.
  const double t = rig.sim.time();
  rig.send(packet(0, 1000));
  EXPECT_FALSE(rig.exchange());
  EXPECT_EQ(rig.receive(), first);
  EXPECT_EQ(rig.sim.time(), t);
  // A gap of 3 frame counts, then a reset.
  rig.send(packet(4, 1000));
  ASSERT_TRUE(rig.exchange());
  rig.receive();
  rig.send(packet(1, 1000));
  ASSERT_TRUE(rig.exchange());
  rig.receive();
  // Bad size and magic: ignored, no step, no reply.
  rig.send(std::vector<std::uint8_t>(20, 0));
  rig.send(packet(2, 1000, 1234));
  EXPECT_FALSE(rig.exchange());
  EXPECT_EQ(rig.receive(), "");
  // PWM 2200: clamped to full speed and counted.
  rig.send(packet(2, 2200));
  ASSERT_TRUE(rig.exchange());
  const auto& c = rig.server.counters();
  EXPECT_EQ(c.duplicates, 1u);
  EXPECT_EQ(c.missed_frames, 3u);
  EXPECT_EQ(c.resets, 1u);
  EXPECT_EQ(c.bad_size, 1u);
  EXPECT_EQ(c.bad_magic, 1u);
  EXPECT_EQ(c.out_of_range_pwm, 1u);
  EXPECT_EQ(c.packets, 5u);
  EXPECT_EQ(c.lockstep_steps, 4u);
  EXPECT_EQ(c.state_messages, 5u);
  EXPECT_NEAR(rig.sim.time(), 4 * 0.004, 1e-12);
  // Silence: the lock-step gives up after the timeout and the simulation free-wheels.
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  rig.server.service(0.0);
  EXPECT_FALSE(rig.server.lockstep());
  EXPECT_EQ(rig.server.counters().stalls, 1u);
  EXPECT_TRUE(rig.server.readyToStep());
}

TEST(ArduPilotServer, StateJsonFrames) {
  sim::UavState s;
  s.t = 1.5;
  s.position = Vec3(1, 2, 3);  // ENU
  s.velocity = Vec3(0.5, -1, 0.25);
  ImuSample imu;
  imu.gyro = Vec3(0.1, 0.2, 0.3);
  imu.accel = Vec3(0, 0, -9.80665);
  const std::string j = ardupilotStateJson(s, imu);
  EXPECT_NE(j.find("\"position\":[2,1,-3]"), std::string::npos) << j;  // NED
  EXPECT_NE(j.find("\"velocity\":[-1,0.5,-0.25]"), std::string::npos) << j;
  EXPECT_NE(j.find("\"quaternion\":["), std::string::npos);
  EXPECT_EQ(std::count(j.begin(), j.end(), '\n'), 2);
}

}  // namespace
}  // namespace hameritt::sitl
