// Simulator throughput: physics steps per second and the real-time factor at the configured
// rate, for (a) the UAV alone in an empty world and (b) the shipped default scenario (full
// neighborhood, moving vehicles and pedestrians, turbulent wind). Each case runs ~5 s of wall
// time; the UAV flies a waypoint loop and the simulation is reset every 120 s of sim time so the
// movers keep moving.
//
// Usage: bench_sim [seconds_per_case]

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "hameritt/generation/generator.h"
#include "hameritt/scenario/share_dir.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/world.h"
#include "hameritt/sim/quadrotor.h"
#include "hameritt/sim/simulator.h"

using hameritt::sim::Simulator;
using hameritt::sim::Vec3;
namespace scenario = hameritt::scenario;

namespace {

struct Result {
  double steps_per_s;
  double rtf;
  long long steps;
  int episodes;
  int crashes;
};

Result run(Simulator& sim, double wall_s) {
  const Vec3 s = sim.uav().position;
  const std::vector<Vec3> loop = {s + Vec3(0, 0, 30), s + Vec3(80, 0, 30), s + Vec3(80, 80, 35),
                                  s + Vec3(0, 80, 30)};
  const int segment = static_cast<int>(20.0 / sim.dt());   // new waypoint every 20 s of sim
  const int episode = static_cast<int>(120.0 / sim.dt());  // reset every 120 s of sim
  long long steps = 0;
  int episodes = 0, crashes = 0;
  std::size_t wp = 0;
  const auto t0 = std::chrono::steady_clock::now();
  double elapsed = 0;
  while (elapsed < wall_s) {
    sim.reset();
    for (int i = 0; i < episode; ++i) {
      if (i % segment == 0) sim.setPositionSetpoint(loop[wp++ % loop.size()], 0.0);
      sim.step();
    }
    steps += episode;
    ++episodes;
    crashes += sim.uav().crashed ? 1 : 0;
    elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  const double rate = static_cast<double>(steps) / elapsed;
  return {rate, rate * sim.dt(), steps, episodes, crashes};
}

}  // namespace

int main(int argc, char** argv) {
  const double wall = argc > 1 ? std::atof(argv[1]) : 5.0;
  const auto params = hameritt::sim::loadQuadrotorUrdf(hameritt::sim::defaultQuadrotorUrdf());
  const hameritt::sim::SimSettings settings;  // 500 Hz, wind on

  {
    scenario::World empty;
    scenario::SimConfig c;
    c.seed = 1;
    c.uav.max_speed = 12;
    c.environment.wind_mean = {3, 1, 0};
    c.environment.gust_intensity = 0.5;
    Simulator sim(empty, c, params, settings);
    const Result r = run(sim, wall);
    std::printf(
        "(a) UAV alone:        %10.0f steps/s  real-time factor %7.1f at %.0f Hz  (%lld steps, "
        "%d/%d episodes crashed)\n",
        r.steps_per_s, r.rtf, settings.physics_rate_hz, r.steps, r.crashes, r.episodes);
  }
  {
    const scenario::World world = scenario::generateWorld(
        scenario::loadWorldParams(scenario::defaultConfigDir() + "/world.json"));
    const std::string dir = scenario::shareDir() + "/scenarios/default";
    const scenario::SimConfig c = scenario::loadSimConfig(dir + "/sim_config.json");
    Simulator sim(world, c, params, settings);
    const Result r = run(sim, wall);
    std::printf(
        "(b) default scenario: %10.0f steps/s  real-time factor %7.1f at %.0f Hz  (%lld steps; "
        "%d/%d episodes crashed; %d static boxes, %d movers)\n",
        r.steps_per_s, r.rtf, settings.physics_rate_hz, r.steps, r.crashes, r.episodes,
        sim.staticObjectCount(), sim.moverCount());
  }
  return 0;
}
