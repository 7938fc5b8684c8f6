// Motor-level flight: rotor speed commands from an external autopilot drive the model directly.
#include <gtest/gtest.h>

#include <cmath>

#include "hameritt/scenario/error.h"
#include "hameritt/sim/quadrotor.h"
#include "hameritt/sim/simulator.h"
#include "sim_test_util.h"

namespace hameritt::sim {
namespace {

using testing::calmConfig;
using testing::emptyWorld;
using testing::sentinel;

SimSettings calmSettings() {
  SimSettings s;
  s.wind = false;
  return s;
}

// Lifts the UAV clear of the ground at hover speed so the ground contact does not mask the
// dynamics, then returns the simulator airborne.
void takeOff(Simulator& sim, double speed_scale = 1.2, double seconds = 0.8) {
  const double w = sim.params().hoverSpeed() * speed_scale;
  sim.setRotorCommands(Eigen::Vector4d::Constant(w));
  sim.step(static_cast<int>(seconds / sim.dt()));
}

TEST(RotorCommands, HoverSpeedBalancesTheWeight) {
  // Without body drag the hover speed must hold the vertical velocity exactly constant.
  QuadrotorParams p = sentinel();
  p.drag_linear.setZero();
  p.drag_quadratic.setZero();
  auto verticalChange = [&](double scale) {
    Simulator sim(emptyWorld(), calmConfig(), p, calmSettings());
    takeOff(sim, 1.1, 0.6);
    EXPECT_FALSE(sim.uav().landed);
    sim.setRotorCommands(Eigen::Vector4d::Constant(scale * p.hoverSpeed()));
    sim.step(static_cast<int>(0.4 / sim.dt()));  // motors settle (> 10 time constants)
    const double v0 = sim.uav().velocity.z();
    sim.step(static_cast<int>(2.0 / sim.dt()));
    EXPECT_NEAR(sim.uav().orientation.w(), 1.0, 1e-9);  // balanced rotors: no torque
    return sim.uav().velocity.z() - v0;
  };
  EXPECT_NEAR(verticalChange(1.0), 0.0, 1e-3);
  // Negative control: 5 % less speed is about 10 % less thrust, -0.1 g for 2 s.
  EXPECT_NEAR(verticalChange(0.95), -2.0 * 9.80665 * (1 - 0.95 * 0.95), 0.05);
}

TEST(RotorCommands, YawTorqueSignFollowsSpinDirection) {
  // Faster ccw rotors (outputs 1 and 2 of quad-X): their reaction torque turns the body cw,
  // i.e. yaw rate about +z (FLU) negative; faster cw rotors turn it ccw.
  const RotorLayout quad_x = quadXLayout(sentinel());
  for (int sign : {1, -1}) {
    Simulator sim(emptyWorld(), calmConfig(), sentinel(), calmSettings());
    takeOff(sim);
    const double w = sim.params().hoverSpeed();
    Eigen::Vector4d cmd;
    for (int o = 0; o < 4; ++o) {
      const bool ccw = o < 2;
      cmd[quad_x[static_cast<std::size_t>(o)]] = w * ((ccw == (sign > 0)) ? 1.05 : 0.95);
    }
    sim.setRotorCommands(cmd);
    sim.step(static_cast<int>(0.3 / sim.dt()));
    const double yaw_rate = sim.uav().angular_velocity.z();
    if (sign > 0)
      EXPECT_LT(yaw_rate, -0.1);
    else
      EXPECT_GT(yaw_rate, 0.1);
    EXPECT_NEAR(sim.uav().angular_velocity.x(), 0.0, 1e-6);
    EXPECT_NEAR(sim.uav().angular_velocity.y(), 0.0, 1e-6);
  }
}

TEST(RotorCommands, MotorsFollowTheTimeConstant) {
  Simulator sim(emptyWorld(), calmConfig(), sentinel(), calmSettings());
  const QuadrotorParams& p = sim.params();
  const double w = 1000.0;
  sim.setRotorCommands(Eigen::Vector4d::Constant(w));
  // One spin-up time constant: 1 - 1/e of the step.
  const int n = static_cast<int>(std::round(p.tau_up / sim.dt()));
  sim.step(n);
  EXPECT_NEAR(sim.uav().rotor_speeds[0] / w, 1.0 - std::exp(-n * sim.dt() / p.tau_up), 1e-9);
  EXPECT_NEAR(sim.uav().rotor_speeds[0] / w, 0.632, 0.01);
  sim.step(10 * n);
  EXPECT_NEAR(sim.uav().rotor_speeds[0], w, 1.0);
  // Spin-down with its own constant.
  sim.setRotorCommands(Eigen::Vector4d::Zero());
  const int m = static_cast<int>(std::round(p.tau_down / sim.dt()));
  const double w0 = sim.uav().rotor_speeds[0];
  sim.step(m);
  EXPECT_NEAR(sim.uav().rotor_speeds[0] / w0, std::exp(-m * sim.dt() / p.tau_down), 1e-9);
  // Out-of-range and NaN commands: clamped, NaN is zero.
  sim.setRotorCommands(Eigen::Vector4d(1e9, -5, std::nan(""), 100));
  sim.step(200);
  EXPECT_NEAR(sim.uav().rotor_speeds[0], p.max_speed, 1.0);
  // Both spin down to zero alike (NaN and -5 are both a zero command).
  EXPECT_LT(sim.uav().rotor_speeds[1], 0.01);
  EXPECT_EQ(sim.uav().rotor_speeds[1], sim.uav().rotor_speeds[2]);
}

TEST(RotorLayout, QuadXFromGeometryAndParsing) {
  // The shipped model lists its rotors in PX4's quad-X order already.
  EXPECT_EQ(quadXLayout(sentinel()), (RotorLayout{0, 1, 2, 3}));
  QuadrotorParams shuffled = sentinel();
  std::swap(shuffled.rotors[0], shuffled.rotors[3]);
  EXPECT_EQ(quadXLayout(shuffled), (RotorLayout{3, 1, 2, 0}));
  QuadrotorParams wrong = sentinel();
  wrong.rotors[0].direction = -1;  // front-right now cw: no quad-X
  EXPECT_THROW(quadXLayout(wrong), scenario::ConfigError);
  EXPECT_EQ(parseRotorLayout("2,0,3,1", "f"), (RotorLayout{2, 0, 3, 1}));
  for (const char* bad : {"", "0,1,2", "0,1,2,2", "0,1,2,4", "0,1,2,3,0", "a,b,c,d", "0,1,2,3x"}) {
    EXPECT_THROW(parseRotorLayout(bad, "~rotor_layout"), scenario::ConfigError) << bad;
  }
}

}  // namespace
}  // namespace hameritt::sim
