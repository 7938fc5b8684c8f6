#include "hameritt/sim/simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/trajectory.h"
#include "hameritt/sim/wind.h"
#include "sim_test_util.h"

namespace hameritt::sim {
namespace {

using testing::calmConfig;
using testing::defaultSimConfig;
using testing::emptyWorld;
using testing::runUntil;
using testing::sentinel;
using testing::shippedWorld;

// Bitwise equality of the integrated UAV state.
bool sameBits(const UavState& a, const UavState& b) {
  auto eq = [](const double* x, const double* y, int n) {
    return std::memcmp(x, y, sizeof(double) * static_cast<std::size_t>(n)) == 0;
  };
  return eq(a.position.data(), b.position.data(), 3) &&
         eq(a.velocity.data(), b.velocity.data(), 3) &&
         eq(a.orientation.coeffs().data(), b.orientation.coeffs().data(), 4) &&
         eq(a.angular_velocity.data(), b.angular_velocity.data(), 3) &&
         eq(a.rotor_speeds.data(), b.rotor_speeds.data(), 4) && a.crashed == b.crashed &&
         a.landed == b.landed;
}

TEST(SimSettings, ValidationNamesTheField) {
  for (double rate : {0.0, -500.0, 10.0, 1e6, std::nan("")}) {
    SimSettings s;
    s.physics_rate_hz = rate;
    try {
      s.validate();
      FAIL() << rate;
    } catch (const scenario::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("physics_rate_hz"), std::string::npos);
    }
    EXPECT_THROW(Simulator(emptyWorld(), calmConfig(), sentinel(), s), scenario::ConfigError);
  }
  SimSettings ok;
  ok.physics_rate_hz = 1000;
  EXPECT_NO_THROW(ok.validate());
  Simulator sim(emptyWorld(), calmConfig(), sentinel(), ok);
  EXPECT_DOUBLE_EQ(sim.dt(), 0.001);
}

TEST(Simulator, StartsLandedAndStaysWithoutCommands) {
  scenario::SimConfig c = calmConfig();
  c.uav.start = {0, 5, -3, 0, 0.7};
  c.uav.start.z = 0;
  Simulator sim(emptyWorld(), c, sentinel(), SimSettings());
  EXPECT_TRUE(sim.uav().landed);
  EXPECT_EQ(sim.uav().position, Vec3(5, -3, 0.05));
  sim.step(1000);
  EXPECT_DOUBLE_EQ(sim.time(), 2.0);
  EXPECT_TRUE(sim.uav().landed);
  EXPECT_FALSE(sim.uav().crashed);
  EXPECT_EQ(sim.uav().position, Vec3(5, -3, 0.05));
  EXPECT_NEAR(sim.uav().specific_force.z(), 9.80665, 1e-9);
}

TEST(Simulator, TakesOffAndHoldsAPositionSetpoint) {
  Simulator sim(emptyWorld(), calmConfig(), sentinel(), SimSettings());
  const Vec3 target(0, 0, 10);
  sim.setPositionSetpoint(target, 0.0);
  double max_climb = 0;
  for (int i = 0; i < 15 * 500; ++i) {
    sim.step();
    max_climb = std::max(max_climb, sim.uav().velocity.z());
  }
  EXPECT_FALSE(sim.uav().landed);
  EXPECT_LE(max_climb, sentinel().max_climb + 0.3);  // climb limit
  EXPECT_GT(max_climb, 2.0);
  double worst = 0;
  for (int i = 0; i < 10 * 500; ++i) {
    sim.step();
    worst = std::max(worst, (sim.uav().position - target).norm());
  }
  EXPECT_LT(worst, 0.3);
  // Hover: rotors near the analytic hover speed, level.
  EXPECT_NEAR(sim.uav().rotor_speeds.mean(), sentinel().hoverSpeed(),
              0.02 * sentinel().hoverSpeed());
  EXPECT_GT((sim.uav().orientation * Vec3::UnitZ()).z(), 0.999);
  // An accelerometer at hover reads the thrust per unit mass: +g along body z.
  EXPECT_NEAR(sim.uav().specific_force.z(), 9.80665, 0.1);
  EXPECT_LT(sim.uav().specific_force.head<2>().norm(), 0.1);
}

TEST(Simulator, FliesASquareOfWaypoints) {
  Simulator sim(emptyWorld(), calmConfig(), sentinel(), SimSettings());
  sim.setPositionSetpoint({0, 0, 10}, 0.0);
  sim.step(10 * 500);
  const std::vector<Vec3> square = {{20, 0, 10}, {20, 20, 10}, {0, 20, 10}, {0, 0, 10}};
  double max_speed = 0;
  for (const Vec3& wp : square) {
    sim.setPositionSetpoint(wp, 0.0);
    double closest = 1e9;
    const bool reached = runUntil(sim, 30.0, [&] {
      closest = std::min(closest, (sim.uav().position - wp).norm());
      max_speed = std::max(max_speed, sim.uav().velocity.head<2>().norm());
      return closest < 1.0;
    });
    EXPECT_TRUE(reached) << "waypoint " << wp.transpose() << " closest " << closest;
    EXPECT_LT(sim.time(), 120.0);
  }
  EXPECT_LE(max_speed, 12.5);
  EXPECT_FALSE(sim.uav().crashed);
}

TEST(Simulator, VelocitySetpointIsLimitedToMaxSpeed) {
  Simulator sim(emptyWorld(), calmConfig(), sentinel(), SimSettings());
  sim.setPositionSetpoint({0, 0, 20}, 0.0);
  sim.step(12 * 500);
  sim.setVelocitySetpoint({30, 0, 0}, 0.0);
  sim.step(15 * 500);
  EXPECT_NEAR(sim.uav().velocity.x(), 12.0, 0.3);
  // Tilt stays within the limit.
  const double tilt = std::acos((sim.uav().orientation * Vec3::UnitZ()).z());
  EXPECT_LT(tilt, sentinel().max_tilt + 0.02);
  EXPECT_GT(tilt, 0.05);  // drag at 12 m/s needs a visible tilt
}

TEST(Simulator, CompensatesSteadyWindAndDriftsWithoutControl) {
  scenario::SimConfig c = calmConfig();
  c.environment.wind_mean = {6, 0, 0};
  c.environment.gust_intensity = 0;
  Simulator sim(emptyWorld(), c, sentinel(), SimSettings());
  EXPECT_EQ(sim.wind(), Vec3(6, 0, 0));
  const Vec3 target(0, 0, 10);
  sim.setPositionSetpoint(target, 0.0);
  sim.step(30 * 500);
  double worst = 0;
  for (int i = 0; i < 5 * 500; ++i) {
    sim.step();
    worst = std::max(worst, (sim.uav().position - target).norm());
  }
  EXPECT_LT(worst, 0.5);
  // Holding against a 6 m/s wind blowing towards +x the craft leans into it (body z to -x).
  EXPECT_LT((sim.uav().orientation * Vec3::UnitZ()).x(), -0.01);

  // Controller loops bypassed: level attitude with hover thrust -> drifts downwind.
  const Vec3 p0 = sim.uav().position;
  sim.setAttitudeSetpoint(Quat::Identity(), sentinel().mass * 9.80665);
  sim.step(5 * 500);
  EXPECT_GT(sim.uav().position.x() - p0.x(), 5.0);
  EXPECT_LT(std::abs(sim.uav().position.y() - p0.y()), 0.5);

  // The same without wind stays put (the drift is the wind's doing).
  Simulator calm(emptyWorld(), calmConfig(), sentinel(), SimSettings());
  calm.setPositionSetpoint(target, 0.0);
  calm.step(30 * 500);
  const Vec3 q0 = calm.uav().position;
  calm.setAttitudeSetpoint(Quat::Identity(), sentinel().mass * 9.80665);
  calm.step(5 * 500);
  EXPECT_LT((calm.uav().position - q0).head<2>().norm(), 0.5);
}

TEST(Wind, TurbulenceIsSeededAndHasTheDrydenIntensity) {
  auto series = [](std::uint64_t seed) {
    DrydenTurbulence d(0.5, seed);
    std::vector<Eigen::Vector3d> out;
    for (int i = 0; i < 100000; ++i) out.push_back(d.step(0.02, 30.0, 6.0));
    return out;
  };
  const auto a = series(11), b = series(11), c = series(12);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  // Sample standard deviations near the MIL-F-8785C sigmas (2000 s, ~80 correlation times).
  const double h = 30.0 * 3.280839895;
  const double sigma_w = 0.1 * 0.5 * 15.0;
  const double sigma_u = sigma_w / std::pow(0.177 + 0.000823 * h, 0.4);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), sq = Eigen::Vector3d::Zero();
  for (const auto& g : a) {
    mean += g;
    sq += g.cwiseProduct(g);
  }
  mean /= a.size();
  const Eigen::Vector3d sd = (sq / a.size() - mean.cwiseProduct(mean)).cwiseSqrt();
  EXPECT_GT(sd.x(), 0.5 * sigma_u);
  EXPECT_LT(sd.x(), 1.5 * sigma_u);
  EXPECT_GT(sd.y(), 0.5 * sigma_u);
  EXPECT_LT(sd.y(), 1.5 * sigma_u);
  EXPECT_GT(sd.z(), 0.5 * sigma_w);
  EXPECT_LT(sd.z(), 1.5 * sigma_w);
  // Zero intensity: no gusts.
  DrydenTurbulence calm(0.0, 11);
  EXPECT_EQ(calm.step(0.002, 30, 6), Eigen::Vector3d::Zero());
}

TEST(Wind, SimulatorWindFollowsTheScenarioSeed) {
  scenario::SimConfig c = calmConfig(5);
  c.environment.wind_mean = {3, -2, 0};
  c.environment.gust_intensity = 0.8;
  auto series = [](const scenario::SimConfig& cfg, bool enabled) {
    SimSettings s;
    s.wind = enabled;
    Simulator sim(emptyWorld(), cfg, sentinel(), s);
    sim.setPositionSetpoint({0, 0, 15}, 0);
    std::vector<Vec3> out;
    for (int i = 0; i < 3000; ++i) {
      sim.step();
      out.push_back(sim.wind());
    }
    return out;
  };
  const auto a = series(c, true);
  EXPECT_EQ(a, series(c, true));
  scenario::SimConfig other = c;
  other.seed = 6;
  EXPECT_NE(a, series(other, true));
  // Turbulence around the mean.
  Vec3 mean = Vec3::Zero();
  for (const auto& w : a) mean += w;
  mean /= a.size();
  EXPECT_NE(a.front(), a.back());
  EXPECT_LT((mean - c.environment.wind_mean).norm(), 3.0);
  // Disabled: still air.
  for (const auto& w : series(c, false)) ASSERT_EQ(w, Vec3::Zero());
}

TEST(Simulator, MoversFollowTheirTrajectoriesExactly) {
  const scenario::SimConfig& c = defaultSimConfig();
  Simulator sim(shippedWorld(), c, sentinel(), SimSettings());
  EXPECT_GT(sim.staticObjectCount(), 4000);
  EXPECT_GE(sim.moverCount(), 20);
  int checked = 0;
  for (int k = 0; k < 40; ++k) {
    sim.step(k % 2 ? 1250 : 1249);  // ~2.5 s apart, at times off the sample grid
    const double t = sim.time();
    const auto states = sim.scenarioEntities();
    ASSERT_EQ(states.size(), c.entities.size());
    for (std::size_t i = 0; i < states.size(); ++i) {
      const auto& se = c.entities[i];
      EXPECT_EQ(states[i].id, se.entity.id);
      if (se.trajectory.empty()) {
        EXPECT_EQ(states[i].box.center, se.entity.box.center);
        continue;
      }
      const auto p = scenario::sampleTrajectory(se.trajectory, t);
      EXPECT_NEAR(states[i].box.center.x(), p.x, 1e-9);
      EXPECT_NEAR(states[i].box.center.y(), p.y, 1e-9);
      EXPECT_NEAR(states[i].box.minZ(), p.z, 1e-9);
      EXPECT_NEAR(states[i].box.yaw, p.yaw, 1e-9);
      if (t > se.trajectory.front().t && t < se.trajectory.back().t &&
          states[i].velocity.norm() > 0.5) {
        // Velocity consistent with the trajectory over a short interval.
        const auto q = scenario::sampleTrajectory(se.trajectory, t + 1e-4);
        const Vec3 fd = Vec3(q.x - p.x, q.y - p.y, q.z - p.z) / 1e-4;
        if ((fd - states[i].velocity).norm() < 1e-3) ++checked;
      }
    }
  }
  EXPECT_GT(checked, 50);
}

TEST(Simulator, FlyingIntoAHouseIsACrashWithItsId) {
  scenario::SimConfig c = calmConfig();
  scenario::ScenarioEntity house;
  house.entity.id = "house_test";
  house.entity.cls = scenario::EntityClass::kHouse;
  house.entity.box = scenario::boxFromPose({30, 0, 0}, 0.3, {12, 10, 7});
  house.role = "vignette";
  c.entities.push_back(house);
  Simulator sim(emptyWorld(), c, sentinel(), SimSettings());
  EXPECT_EQ(sim.staticObjectCount(), 1);
  sim.setPositionSetpoint({0, 0, 4}, 0.0);
  sim.step(8 * 500);
  EXPECT_FALSE(sim.uav().crashed);
  sim.setVelocitySetpoint({5, 0, 0}, 0.0);
  ASSERT_TRUE(runUntil(sim, 20.0, [&] { return sim.uav().crashed; }));
  EXPECT_EQ(sim.uav().crashed_into, "house_test");
  EXPECT_NEAR(sim.uav().crash_time, sim.time(), 1e-12);
  // Crashed at the wall (house front at x ~ 30 - 6 along its rotated body).
  EXPECT_GT(sim.uav().position.x(), 20.0);
  EXPECT_LT(sim.uav().position.x(), 26.0);
  // The UAV stops and ignores further commands.
  const Vec3 p = sim.uav().position;
  sim.setVelocitySetpoint({-5, 0, 0}, 0.0);
  sim.step(500);
  EXPECT_EQ(sim.uav().position, p);
  EXPECT_EQ(sim.uav().velocity, Vec3::Zero());
  EXPECT_EQ(sim.uav().rotor_speeds, Eigen::Vector4d::Zero());
  EXPECT_TRUE(sim.uav().crashed);
  // reset() clears the crash.
  sim.reset();
  EXPECT_FALSE(sim.uav().crashed);
  EXPECT_TRUE(sim.uav().landed);
}

TEST(Simulator, TakingOffInsideAWorldHouseCrashesIntoIt) {
  const scenario::World& world = shippedWorld();
  const auto it = std::find_if(
      world.entities().begin(), world.entities().end(),
      [](const scenario::Entity& e) { return e.cls == scenario::EntityClass::kHouse; });
  ASSERT_NE(it, world.entities().end());
  scenario::SimConfig c = calmConfig();
  c.uav.start = {0, it->box.center.x(), it->box.center.y(), 0, 0};
  Simulator sim(world, c, sentinel(), SimSettings());
  sim.setPositionSetpoint({it->box.center.x(), it->box.center.y(), 20}, 0);
  ASSERT_TRUE(runUntil(sim, 5.0, [&] { return sim.uav().crashed; }));
  EXPECT_EQ(sim.uav().crashed_into, it->id);
}

TEST(Simulator, SoftLandingIsNotACrashButAFallIs) {
  Simulator sim(emptyWorld(), calmConfig(), sentinel(), SimSettings());
  sim.setPositionSetpoint({0, 0, 6}, 0.0);
  sim.step(8 * 500);
  ASSERT_FALSE(sim.uav().landed);
  sim.setVelocitySetpoint({0, 0, -1}, 0.0);
  ASSERT_TRUE(runUntil(sim, 20.0, [&] { return sim.uav().landed; }));
  EXPECT_FALSE(sim.uav().crashed);
  EXPECT_NEAR(sim.uav().position.z(), 0.05, 1e-12);
  sim.step(2 * 500);  // stays down while commanded down
  EXPECT_TRUE(sim.uav().landed);
  EXPECT_FALSE(sim.uav().crashed);
  // Takes off again.
  sim.setPositionSetpoint({0, 0, 10}, 0.0);
  sim.step(15 * 500);
  EXPECT_NEAR(sim.uav().position.z(), 10.0, 0.3);
  // Motors cut at 10 m: a hard ground impact.
  sim.disarm();
  ASSERT_TRUE(runUntil(sim, 10.0, [&] { return sim.uav().crashed; }));
  EXPECT_EQ(sim.uav().crashed_into, "ground");
  EXPECT_FALSE(sim.uav().landed);
}

// A fixed command script on the default scenario (turbulent wind, movers, the full world).
void flyScript(Simulator& sim, int steps) {
  const Vec3 s = sim.uav().position;
  for (int i = 0; i < steps; ++i) {
    if (i == 0) sim.setPositionSetpoint(s + Vec3(0, 0, 25), 0.5);
    if (i == 2500) sim.setVelocitySetpoint({4, -2, 0.5}, 0.2);
    if (i == 4000) sim.setPositionSetpoint(s + Vec3(5, 5, 30), -1.0);
    sim.step();
  }
}

TEST(Simulator, IdenticalInputsGiveBitIdenticalStatesAndResetReplays) {
  const scenario::SimConfig& c = defaultSimConfig();
  ASSERT_GT(c.environment.gust_intensity, 0.0);
  Simulator a(shippedWorld(), c, sentinel(), SimSettings());
  Simulator b(shippedWorld(), c, sentinel(), SimSettings());
  flyScript(a, 5000);
  flyScript(b, 5000);
  EXPECT_FALSE(a.uav().crashed);
  EXPECT_GT(a.uav().position.z(), 15.0);
  EXPECT_TRUE(sameBits(a.uav(), b.uav()));
  EXPECT_EQ(a.wind(), b.wind());
  const UavState first = a.uav();
  a.reset();
  EXPECT_EQ(a.time(), 0.0);
  EXPECT_TRUE(a.uav().landed);
  flyScript(a, 5000);
  EXPECT_TRUE(sameBits(a.uav(), first));
  // A different command sequence gives a different state (the comparison can fail).
  b.setVelocitySetpoint({0, 3, 0}, 0);
  b.step();
  EXPECT_FALSE(sameBits(a.uav(), b.uav()));
}

// An avoid scenario's aircraft is a kinematic mover in ground truth (its trajectory gives the
// body centre) and a contact with it is a crash into its id; the same aircraft passing 5 m
// above the hovering UAV is not (the control).
TEST(Simulator, AircraftAreMoversAndAContactIsACrash) {
  auto run = [](double pass_z, std::vector<EntityState>* truth_at_4s) {
    scenario::SimConfig c = calmConfig();
    scenario::Aircraft a;
    a.id = "aircraft_1";
    a.model = "fixed_wing";
    a.size = Vec3(1.2, 2.0, 2.0);  // tall: the hover height settles within +- 1 m
    a.trajectory = {{0.0, -60.0, 0.0, pass_z, 0.0}, {12.0, 60.0, 0.0, pass_z, 0.0}};
    c.aircraft.push_back(a);
    c.duration = 20.0;
    Simulator sim(emptyWorld(), c, sentinel(), SimSettings());
    sim.setPositionSetpoint({0, 0, 10}, 0.0);
    runUntil(sim, 4.0, [] { return false; });
    *truth_at_4s = sim.scenarioEntities();
    runUntil(sim, 8.0, [&] { return sim.uav().crashed; });
    return sim.uav();
  };
  std::vector<EntityState> truth;
  const UavState hit = run(10.0, &truth);
  ASSERT_EQ(truth.size(), 1u);
  EXPECT_EQ(truth[0].id, "aircraft_1");
  EXPECT_EQ(truth[0].role, "aircraft");
  EXPECT_EQ(truth[0].cls, scenario::EntityClass::kAircraft);
  EXPECT_NEAR(truth[0].box.center.x(), -20.0, 0.05);
  EXPECT_NEAR(truth[0].box.center.z(), 10.0, 1e-9);
  EXPECT_NEAR(truth[0].velocity.x(), 10.0, 1e-9);
  EXPECT_TRUE(hit.crashed);
  EXPECT_EQ(hit.crashed_into, "aircraft_1");
  const UavState clear = run(15.0, &truth);
  EXPECT_FALSE(clear.crashed);
}

}  // namespace
}  // namespace hameritt::sim
