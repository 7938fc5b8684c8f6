#include "hameritt/sim/quadrotor.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <regex>
#include <string>

#include "hameritt/scenario/error.h"
#include "sim_test_util.h"

namespace hameritt::sim {
namespace {

using scenario::ConfigError;
using testing::sentinel;

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = "/tmp/hameritt_sim_test_" + name + ".urdf";
  std::ofstream(path) << text;
  return path;
}

// Expects loading `text` to fail with a message naming the file and containing `what`.
void expectUrdfError(const std::string& name, const std::string& text, const std::string& what) {
  const std::string path = writeTemp(name, text);
  try {
    loadQuadrotorUrdf(path);
    FAIL() << "no error for " << name;
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  }
  std::remove(path.c_str());
}

TEST(QuadrotorUrdf, ShippedModelHasExpectedMassInertiaAndRotors) {
  const QuadrotorParams& p = sentinel();
  EXPECT_EQ(p.name, "sentinel");
  EXPECT_NEAR(p.mass, 1.04, 1e-12);
  // Base link plus four 20 g rotors at (+-0.106066, +-0.106066, 0.03) by the parallel-axis rule.
  const double hub2_xy = 2 * 0.106066 * 0.106066;
  const double ixx = 0.0052 + 4 * (1e-6 + 0.02 * (0.106066 * 0.106066 + 0.03 * 0.03));
  const double izz = 0.0095 + 4 * (2e-6 + 0.02 * hub2_xy);
  EXPECT_NEAR(p.inertia(0, 0), ixx, 1e-12);
  EXPECT_NEAR(p.inertia(1, 1), ixx, 1e-12);
  EXPECT_NEAR(p.inertia(2, 2), izz, 1e-12);
  EXPECT_NEAR(p.inertia(0, 1), 0.0, 1e-12);
  ASSERT_EQ(p.rotors.size(), 4u);
  int direction_sum = 0;
  for (const Rotor& r : p.rotors) {
    EXPECT_NEAR(r.position.head<2>().norm(), 0.15, 1e-5) << r.joint;  // 0.30 m diagonal
    EXPECT_NEAR(r.position.z(), 0.03, 1e-12);
    direction_sum += r.direction;
  }
  EXPECT_EQ(direction_sum, 0);
  EXPECT_DOUBLE_EQ(p.kf, 1.3e-6);
  EXPECT_DOUBLE_EQ(p.km, 2.08e-8);
  EXPECT_DOUBLE_EQ(p.max_speed, 2600);
  EXPECT_DOUBLE_EQ(p.tau_up, 0.02);
  EXPECT_NEAR(p.max_tilt, 35.0 * M_PI / 180.0, 1e-12);
  EXPECT_DOUBLE_EQ(p.max_horizontal_speed, 12.0);
  EXPECT_EQ(p.collision_size, Vec3(0.34, 0.34, 0.10));
  // Thrust-to-weight between 2.5 and 4 and a hover speed well inside the motor range.
  const double tw = p.maxThrust() / (p.mass * 9.80665);
  EXPECT_GT(tw, 2.5);
  EXPECT_LT(tw, 4.0);
  EXPECT_GT(p.hoverSpeed(), 0.4 * p.max_speed);
  EXPECT_LT(p.hoverSpeed(), 0.7 * p.max_speed);
  ASSERT_EQ(p.cameras.size(), 2u);
  EXPECT_EQ(p.cameras[0].name, "down");
  EXPECT_NEAR(p.cameras[0].rpy.y(), M_PI / 2, 1e-5);
  EXPECT_EQ(p.cameras[1].name, "front");
  EXPECT_EQ(p.cameras[1].xyz, Vec3(0.12, 0, -0.03));
  EXPECT_NEAR(p.cameras[1].rpy.y(), 11.38 * M_PI / 180.0, 1e-5);
}

TEST(QuadrotorUrdf, BadFilesAreConfigErrorsNamingFileAndElement) {
  const std::string good = readFile(defaultQuadrotorUrdf());
  ASSERT_FALSE(good.empty());
  EXPECT_THROW(loadQuadrotorUrdf("/nonexistent/sentinel.urdf"), ConfigError);
  expectUrdfError("malformed", good.substr(0, good.size() / 2), "URDF");
  expectUrdfError("no_ext",
                  std::regex_replace(good, std::regex("\n  <hameritt>[\\s\\S]*</hameritt>"), ""),
                  "<hameritt>");
  expectUrdfError("bad_dir",
                  std::regex_replace(good, std::regex("direction=\"cw\""), "direction=\"up\"",
                                     std::regex_constants::format_first_only),
                  "<rotor joint=\"rotor_2_joint\">");
  expectUrdfError("bad_kf", std::regex_replace(good, std::regex("kf=\"1.3e-6\""), "kf=\"abc\""),
                  "<rotor_model>");
  expectUrdfError("weak_motors",
                  std::regex_replace(good, std::regex("max_speed=\"2600\""), "max_speed=\"1000\""),
                  "thrust-to-weight");
  expectUrdfError("no_drag", std::regex_replace(good, std::regex("<drag [^>]*/>"), ""), "<drag>");
  expectUrdfError("three_rotors",
                  std::regex_replace(
                      std::regex_replace(
                          good, std::regex("<joint name=\"rotor_3_joint\"[\\s\\S]*?</joint>"), ""),
                      std::regex("<link name=\"rotor_3\">[\\s\\S]*?</link>"), ""),
                  "<rotor joint=\"rotor_3_joint\">");
}

TEST(Mixer, ReproducesFeasibleWrenches) {
  const QuadrotorParams& p = sentinel();
  const Mixer mixer(p);
  const double t = p.mass * 9.80665;
  for (const Vec3& tau : {Vec3(0, 0, 0), Vec3(0.05, -0.03, 0.01), Vec3(-0.1, 0.1, -0.02)}) {
    double thrust;
    Vec3 torque;
    mixer.wrench(mixer.mix(t, tau), &thrust, &torque);
    EXPECT_NEAR(thrust, t, 1e-9);
    EXPECT_NEAR((torque - tau).norm(), 0.0, 1e-9);
  }
  // Saturated: full thrust and a large yaw demand keep the roll/pitch torque.
  double thrust;
  Vec3 torque;
  mixer.wrench(mixer.mix(0.95 * p.maxThrust(), Vec3(0.3, 0, 1.0)), &thrust, &torque);
  EXPECT_NEAR(torque.x(), 0.3, 1e-9);
  EXPECT_LT(torque.z(), 1.0);
}

}  // namespace
}  // namespace hameritt::sim
