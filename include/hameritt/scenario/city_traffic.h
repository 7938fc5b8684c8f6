#pragma once
// Signalised traffic and crowds of the city world type, precomputed per scenario: a fixed-time
// signal plan at every intersection on an arterial, ambient cars that follow each other on the
// arterial lanes with the Intelligent Driver Model and obey the signals, and pedestrians who
// stroll the sidewalks, cross at the crosswalks on the signals, jaywalk mid-block or queue at
// the bus stops. Deterministic by seed.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hameritt/scenario/catalog.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/traffic_clearance.h"
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

// One ambient car's trajectory over [0, duration] (its model, colour and lane ring are those of
// the episode's car of the same index).
struct CityCar {
  Trajectory trajectory;
};

// One pedestrian of the crowd. activity: walking (strolls along a block's sidewalk, pausing
// between them), crossing (back and forth over a signalised crosswalk, each time while the
// crossed street is red), jaywalking (back and forth across a local street mid-block, off the
// signals) or queuing (standing at a bus stop; the trajectory is empty and `pose` is where).
struct CityPedestrian {
  std::string activity;
  std::string clothing_color;
  double height = 1.7;
  TrajectoryPoint pose;  // the first pose
  Trajectory trajectory;
};

// A traffic episode: the ambient cars and crowd of a city world simulated once over `length`
// seconds, shared by every scenario of a batch that draws it (each sees a window of it).
// Compact: each lane piece's polyline (a link between boxes, a straight or turning connector
// across a box, a loop beyond the tile) is stored once; each car's path is a list of pieces,
// each starting where the previous one ends, and its motion knots (t, s) of its arc length s
// along the joined path, between which the car moves at constant speed; every simulated
// position lies within 10 cm of the interpolation. A pedestrian walks straight lines between
// keyframes (t, x, y, yaw), stored exactly as a scenario's trajectory holds them.
struct TrafficEpisode {
  struct Lane {
    std::string name;
    std::vector<geometry::Vec2> points;  // open, at least 2 points
  };
  struct Car {
    std::string vehicle_class, make, model, color;
    geometry::Vec3 size{4.5, 1.8, 1.5};  // length, width, height (m)
    std::vector<int> path;               // indices into `lanes`, driven in order
    std::vector<double> knots;           // t0, s0, t1, s1, ... (t strictly increasing from 0)
  };
  int index = 0;
  double length = 0.0;  // seconds
  std::uint64_t world_fingerprint = 0;
  SignalPlan plan;  // at episode time
  std::vector<Lane> lanes;
  std::vector<Car> cars;
  std::vector<CityPedestrian> pedestrians;  // over [0, length] and a little beyond
};

// The length of every traffic episode (s): a scenario of duration d starts at an offset in
// [0, kTrafficEpisodeLength - d]; scenarios longer than half of it simulate their own cars.
constexpr double kTrafficEpisodeLength = 1800.0;

// "traffic_episode_03.json": the file of episode `index` beside a batch's world.json.
std::string trafficEpisodeFileName(int index);

// The episode file's bytes, and its strict reader (ConfigError naming the file, the JSON path and
// what was expected).
std::string trafficEpisodeJson(const TrafficEpisode& e);
TrafficEpisode parseTrafficEpisode(const std::string& text, const std::string& file);

// Lowercase hex SHA-256 (FIPS 180-4) of `bytes`.
std::string sha256Hex(const std::string& bytes);

// Car `car`'s trajectory over the episode window [offset, offset + duration], shifted to start
// at 0: positions and yaw interpolated from the knots along the lane, rounded to the millimetre.
Trajectory episodeCarWindow(const TrafficEpisode& e, std::size_t car, double offset,
                            double duration);

// The scenario entity (role "traffic") of car `car` of the episode moving along `window`.
ScenarioEntity episodeCarEntity(const TrafficEpisode& e, std::size_t car, Trajectory window,
                                const std::string& id);

// Pedestrian `ped`'s trajectory over the episode window [offset, offset + duration], shifted to
// start at 0 (empty for a pedestrian who stands).
Trajectory episodePedestrianWindow(const TrafficEpisode& e, std::size_t ped, double offset,
                                   double duration);

// The scenario entity (role "pedestrian") of a crowd pedestrian moving along `window` (its box
// at the window's first pose, or at `p.pose` when it stands).
ScenarioEntity cityPedestrianEntity(const CityPedestrian& p, Trajectory window,
                                    const std::string& id);

// The signal plan a scenario sees when it starts at `offset` of a plan: every offset shifted.
SignalPlan shiftedSignalPlan(const SignalPlan& plan, double offset);

// Episode `index` of `world`, simulated once per process (thread-safe, deterministic: a function
// of the world and the index), with its file's bytes and their SHA-256.
struct SharedTrafficEpisode {
  TrafficEpisode episode;                   // as read back from `text`
  std::shared_ptr<const std::string> text;  // null for a scenario's own cars (not shared)
  std::string sha256;
  std::vector<Trajectory> trajectories;  // each car's, over the whole episode
  // Each car's footprint blocks (traffic_clearance.h) over the whole episode, for the scenarios
  // that withhold the cars that come near their own; empty for a scenario's own cars.
  std::vector<ClearanceBlocks> clearance;
  // The grid of `clearance` (traffic_clearance.h): which cars are where in each block.
  ClearanceIndex clearance_index;
};
std::shared_ptr<const SharedTrafficEpisode> cityTrafficEpisode(const World& world, int index,
                                                               const IdmParams& idm = {});

// The draw of a city scenario's traffic: the episode it is a window of (-1: a scenario longer
// than half an episode simulates its own cars), the window's start and the signal plan it sees.
// A function of the world, the seed and whether the duration exceeds half an episode, so that
// the generator knows the plan before it plans the mission's own vehicles.
struct CityTrafficDraw {
  int episode = -1;
  double offset = 0.0;
  SignalPlan plan;
};
CityTrafficDraw drawCityTraffic(const World& world, std::uint64_t seed, double duration,
                                const IdmParams& idm = {});
// The episode of drawCityTraffic(world, seed, d) for any d up to half an episode.
int drawCityTrafficEpisode(const World& world, std::uint64_t seed);

struct CityTraffic {
  SignalPlan plan;
  std::vector<CityCar> cars;
  std::vector<CityPedestrian> pedestrians;  // trajectories: the scenario's window
  // The episode the cars and pedestrians are a window of (car i is the episode's car i, and
  // pedestrian i its pedestrian i); shared by a batch when episode->text is set.
  std::shared_ptr<const SharedTrafficEpisode> episode;
  double offset = 0.0;
};

// The signal plan of a city world: one intersection per interior street node that an arterial
// passes, in node order, with offsets drawn from `seed`.
SignalPlan citySignalPlan(const World& world, std::uint64_t seed);

// The traffic and crowd of a city scenario of `duration` seconds (world.params().city holds the
// densities and signal timing). Throws GenerationError when the world is not a city.
// trajectories false: when the traffic is a window of a shared episode, the cars and the
// pedestrians come without trajectories (each pedestrian with its attributes and first pose),
// for a caller that writes the episode reference instead of them (a batch); a scenario of its
// own cars is returned whole.
CityTraffic simulateCityTraffic(const World& world, std::uint64_t seed, double duration,
                                const IdmParams& idm = {}, bool trajectories = true);

// Upper bounds on the number of cars and pedestrians simulateCityTraffic() returns for `world`
// (the generator sizes its id pools with them).
int cityCarBound(const World& world);
int cityPedestrianBound(const World& world);

}  // namespace hameritt::scenario
