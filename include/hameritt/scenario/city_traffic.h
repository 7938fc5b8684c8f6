#pragma once
// Signalised traffic and crowds of the city world type, precomputed per scenario: a fixed-time
// signal plan at every intersection on an arterial, ambient cars that follow each other on the
// arterial lanes with the Intelligent Driver Model and obey the signals, and pedestrians who
// stroll the sidewalks, cross at the crosswalks on the signals, jaywalk mid-block or queue at
// the bus stops. Deterministic by seed.

#include <cstdint>
#include <string>
#include <vector>

#include "hameritt/scenario/catalog.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

// Car-following parameters of the Intelligent Driver Model (Treiber, Hennecke and Helbing 2000,
// "Congested traffic states in empirical observations and microscopic simulations").
struct IdmParams {
  double time_gap = 1.4;           // desired time headway T (s)
  double min_gap = 2.0;            // standstill gap s0 (m); the bumper gap never falls below it
  double max_accel = 1.5;          // a (m/s^2)
  double comfort_decel = 2.0;      // b (m/s^2)
  double yellow_stop_decel = 3.5;  // a car stops for a yellow when it can at this deceleration
  double step = 0.2;               // integration step (s)
  double warm_up = 60.0;           // simulated before t = 0 so that queues exist at the start (s)
};

// One ambient car: its model, colour, lane and trajectory over [0, duration].
struct CityCar {
  const catalog::CarModel* model = nullptr;
  std::string color;
  std::string lane;  // "lane_<corridor>_<direction><lane>"
  Trajectory trajectory;
};

// One pedestrian of the crowd. activity: walking (a sidewalk stroll), crossing (at a signalised
// crosswalk while the crossed street is red), jaywalking (mid-block, off the signals) or queuing
// (standing at a bus stop; the trajectory is empty and `pose` is where).
struct CityPedestrian {
  std::string activity;
  std::string clothing_color;
  double height = 1.7;
  TrajectoryPoint pose;  // the first pose
  Trajectory trajectory;
};

struct CityTraffic {
  SignalPlan plan;
  std::vector<CityCar> cars;
  std::vector<CityPedestrian> pedestrians;
};

// The signal plan of a city world: one intersection per interior street node that an arterial
// passes, in node order, with offsets drawn from `seed`.
SignalPlan citySignalPlan(const World& world, std::uint64_t seed);

// The traffic and crowd of a city scenario of `duration` seconds (world.params().city holds the
// densities and signal timing). Throws GenerationError when the world is not a city.
CityTraffic simulateCityTraffic(const World& world, std::uint64_t seed, double duration,
                                const IdmParams& idm = {});

// Upper bounds on the number of cars and pedestrians simulateCityTraffic() returns for `world`
// (the generator sizes its id pools with them).
int cityCarBound(const World& world);
int cityPedestrianBound(const World& world);

}  // namespace hameritt::scenario
