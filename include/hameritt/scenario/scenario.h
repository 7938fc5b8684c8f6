#pragma once
// The scenario data model: the mission description (what a client algorithm is told) and the
// simulation configuration (what the simulator needs). Written as mission.json and
// sim_config.json; see docs/reference/formats.md.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "hameritt/geometry/polygon.h"
#include "hameritt/geometry/time_window.h"
#include "hameritt/scenario/entity.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

constexpr int kSchemaVersion = 1;

// follow: pursuit's moving target, found, then followed inside an envelope (phases search ->
// follow). track: pursuit's scene with 1-2 moving targets, found, then kept in a camera's view
// (phases search -> track).
enum class ScenarioClass { kAreaSearch, kRouteSearch, kPursuit, kAvoid, kFollow, kTrack };
const char* toString(ScenarioClass c);
bool parseScenarioClass(const std::string& s, ScenarioClass* out);

// A timed pose sample of a moving entity; the simulator interpolates linearly in position and
// along the shorter arc in yaw between samples, and holds the last sample afterwards.
struct TrajectoryPoint {
  double t = 0, x = 0, y = 0, z = 0, yaw = 0;
};
using Trajectory = std::vector<TrajectoryPoint>;
// The pose of a trajectory at time t (clamped to its first and last samples).
TrajectoryPoint sampleTrajectory(const Trajectory& traj, double t);
// The same, for a caller that knows that the first point later than t is among points
// [lo, hi) of the trajectory (front().t < t < back().t): searches only there.
TrajectoryPoint sampleTrajectoryIn(const Trajectory& traj, double t, std::size_t lo,
                                   std::size_t hi);

// Soft spatial constraint: where the target is expected, optionally only within a window.
struct AreaOfInterest {
  std::string id;
  geometry::Polygon polygon;
  geometry::TimeWindow window;
};

// Hard spatial constraint: the UAV must not enter the polygon between alt_min and alt_max
// (metres above ground; absent means unbounded) while the window is active.
struct KeepOutZone {
  std::string id;
  geometry::Polygon polygon;
  std::optional<double> alt_min;
  std::optional<double> alt_max;
  geometry::TimeWindow window;
  std::string purpose;  // vantage_denial | access_denial | restricted
  // A moving zone (one that escorts a hostile vehicle): its reference point over time
  // ({t, x, y}; z and yaw unused). The polygon is given at the first sample and moves with the
  // point (kozPolygonAt). Empty: the zone is static.
  Trajectory motion;
};

// The zone's polygon at time t: translated by motion(t) - motion(first sample).
geometry::Polygon kozPolygonAt(const KeepOutZone& k, double t);

// One cell of an AOI's prior grid.
struct PriorCell {
  std::string id;
  int row = 0;
  int col = 0;
  geometry::Polygon polygon;
  double probability = 0.0;
};

// The prior belief over where the target is inside one AOI: a 2^depth x 2^depth grid of
// sub-quadrants whose probabilities sum to 1.
struct AreaPrior {
  std::string aoi_id;
  int depth = 1;
  std::vector<PriorCell> cells;
};

// A route of interest along streets with its search band.
struct RouteOfInterest {
  std::string id;
  std::vector<geometry::Vec2> polyline;
  std::vector<std::string> streets;
  double band_width = 0.0;
  geometry::Polygon band;
};

enum class RelationOp {
  kNextTo,
  kNotNextTo,
  kOnTopOf,
  kNotOnTopOf,
  kOrthogonalTo,
  kInFrontOf,
  kRightOf,
  kLeftOf,
  kPartOf,
};
// "NEXT_TO", ..., "PART_OF"; with eventually = true, "EVENTUALLY_NEXT_TO" and so on.
std::string toString(RelationOp op, bool eventually = false);
bool parseRelationOp(const std::string& s, RelationOp* op, bool* eventually);

// [related] [OPERATOR] [target] [related attributes], with the geometric evidence that made
// it true. For PART_OF the related entity is a group.
struct SceneRelation {
  std::string related_id;
  std::string related_class;  // entity class, or "group"
  Attributes related_attributes;
  RelationOp op = RelationOp::kNextTo;
  bool eventually = false;
  std::string target_id;
  // Evidence at the time the relation holds (t = 0, or `time` for EVENTUALLY_*).
  double distance = 0.0;     // footprint-to-footprint, metres
  double bearing_deg = 0.0;  // of the related centre in the target body frame, CCW, [0, 360)
  double dz = 0.0;           // target min z - related max z
  bool line_of_sight = false;
  std::optional<double> time;  // first time it holds (EVENTUALLY_* only)
};

// What the client is asked to find or track.
struct TargetDescription {
  std::string id;
  std::string cls = "car";
  std::string vehicle_class;
  std::string make;
  std::string model;
  std::string color;
};

struct Objective {
  std::string type;  // find | track | reach (avoid: fly to the phase's goal)
  std::string text;
  std::vector<TargetDescription> targets;
};

// The geodetic origin of the local ENU frame.
struct GeoOrigin {
  double latitude = 42.4851;
  double longitude = -71.1873;
  double altitude = 40.0;
};

// A mission's phases run one after another; the mission succeeds only when every phase does.
// search: ends when the targets are found. follow: keep one moving target inside an envelope
// behind and above it for `duration` seconds. track: keep the targets in a camera's view for
// `duration` seconds. avoid: reach a goal among other aircraft without losing separation.
enum class PhaseType { kSearch, kFollow, kTrack, kAvoid };
// "search", "follow", "track", "avoid".
const char* toString(PhaseType t);
bool parsePhaseType(const std::string& s, PhaseType* out);

// The follow envelope in the target's frame (x along its heading, z up) and the phase's
// success test: inside at least min_inside_fraction of the phase, never outside longer than
// max_outside_s. The phase's scored `duration` starts at the vehicle's first entry into the
// envelope after the find, or approach_s after the find if it has not entered by then.
struct FollowPhaseSpec {
  double distance = 15.0;            // d*, metres behind the target
  double distance_tolerance = 5.0;   // D, horizontal radius around that point
  double height = 20.0;              // h*, metres above the target
  double height_tolerance = 5.0;     // H
  double min_inside_fraction = 0.8;  // of the phase
  double max_outside_s = 10.0;
  double approach_s = 0.0;  // allowance from the find to the envelope, seconds
};

// When a target counts as tracked in a frame, and the phase's success test: tracked at least
// min_tracked_fraction of the phase and every loss reacquired within max_reacquire_s.
struct TrackPhaseSpec {
  double min_visible_fraction = 0.5;
  double min_box_area = 400.0;  // px^2
  double min_tracked_fraction = 0.7;
  double max_reacquire_s = 10.0;
};

// The goal of an avoid phase, the shortest 3D path to it from the phase's start (the
// generator's, for SPL), and the separation to keep from every other aircraft: a loss is
// closer than min_horizontal_separation horizontally while closer than
// min_vertical_separation vertically.
struct AvoidPhaseSpec {
  geometry::Vec3 goal{0, 0, 0};
  double goal_radius = 5.0;
  double shortest_path_m = 0.0;
  double min_horizontal_separation = 5.0;
  double min_vertical_separation = 3.0;
};

// One phase; only the spec of its type is read and written.
struct MissionPhase {
  std::string id;
  PhaseType type = PhaseType::kSearch;
  std::vector<std::string> targets;  // objective target ids (none for avoid)
  std::optional<double> duration;    // follow and track: seconds from the phase's start
  FollowPhaseSpec follow;
  TrackPhaseSpec track;
  AvoidPhaseSpec avoid;
};

struct Mission {
  std::string scenario_id;
  ScenarioClass cls = ScenarioClass::kAreaSearch;
  std::uint64_t seed = 0;
  GeoOrigin origin;
  double time_limit = 0.0;
  Objective objective;
  std::vector<AreaOfInterest> aois;
  std::vector<KeepOutZone> kozs;
  std::vector<AreaPrior> priors;
  std::vector<RouteOfInterest> routes;
  std::vector<SceneRelation> relations;
  // Empty: the class's one phase (search, or pursuit's find-then-keep-in-view).
  std::vector<MissionPhase> phases;
};

// An entity added by the scenario (targets, confusers, traffic, pedestrians), with its timed
// trajectory when it moves (empty for a parked car).
struct ScenarioEntity {
  Entity entity;
  std::string role;  // target | confuser | traffic | pedestrian | vignette
  Trajectory trajectory;
};

// A named group of entities (PART_OF relations refer to groups).
struct Group {
  std::string id;
  std::string kind;  // block | convoy | vignette
  std::vector<std::string> members;
};

struct Environment {
  double time_of_day = 12.0;  // hours, local solar time
  double snow = 0, rain = 0, dust = 0, fog = 0;  // intensities in [0, 1]
  double foliage = 1.0;                          // density in [0, 1]
  geometry::Vec3 wind_mean{0, 0, 0};             // ENU m/s, the air's velocity
  double gust_intensity = 0.0;                   // [0, 1]
};

struct CameraSpec {
  std::string name;
  geometry::Vec3 mount_xyz{0, 0, 0};  // body frame (FLU), metres
  geometry::Vec3 mount_rpy{0, 0, 0};  // degrees, roll-pitch-yaw; positive pitch looks down
  int width = 640;
  int height = 480;
  double hfov_deg = 90.0;
  double rate_hz = 10.0;
  std::vector<std::string> modalities;  // rgb, depth, segmentation, instances
};

// A perception-only flight over the targets, planned by the generator with
// planning::planLookAtPath: climb at the start, hover until the moving targets have stopped,
// then visit a viewpoint of each. Written even when planning fails (status says why).
struct PerceptionPath {
  std::string status;                     // exact, approximate, no_solution, invalid_start, ...
  std::string camera;                     // payload camera the viewpoints are planned for
  std::vector<std::string> targets_seen;  // targets verified in the camera image on the path
  Trajectory trajectory;                  // UAV {t, x, y, z, yaw}, strictly increasing t
};

struct UavSpec {
  std::string model = "sentinel";
  TrajectoryPoint start;  // t = 0
  double altitude_min = 20.0;
  double altitude_max = 60.0;
  double max_speed = 12.0;
  std::vector<CameraSpec> cameras;
  std::optional<PerceptionPath> perception_path;  // absent when the generator skipped it
};

struct Perturbations {
  double gaussian_noise_std = 0.0;  // fraction of full scale
  double salt_pepper_probability = 0.0;
  double motion_blur_px = 0.0;
};

// A non-cooperative aircraft of an avoid scenario on a scripted trajectory (the simulator
// moves it kinematically along it). Size is the body's length, wingspan and height (m).
// The fastest an aircraft may move between two trajectory samples (m/s): a faster step is a
// jump, and the trajectory is not continuous.
constexpr double kMaxAircraftSpeed = 60.0;
struct Aircraft {
  std::string id;
  std::string model;  // fixed_wing | quadrotor
  geometry::Vec3 size{1, 1, 0.3};
  Trajectory trajectory;  // at least two samples, strictly increasing t
};

// Where a scenario generated from a spec came from: the spec file, the hash of its sources
// (imports and --param overrides included), the sampler and the values drawn for it.
struct SpecProvenance {
  std::string file;
  std::uint64_t hash = 0;
  std::string sampler;  // random | halton
  std::vector<std::pair<std::string, std::variant<double, bool>>> values;
};

// The signal phase of one approach axis of a signalised intersection at a time.
enum class SignalState {
  kGreen,      // through traffic may enter
  kYellow,     // through traffic may enter only when it cannot stop in time
  kLeftArrow,  // protected left turns only; through traffic waits
  kRed,        // nobody of this axis enters (the other axis moves, or all-red clearance)
};
// "green", "yellow", "left", "red".
const char* toString(SignalState s);

// One signalised intersection of the city's traffic plan: the street node, the direction and
// right-of-way of its two streets (axis 0 runs roughly north-south, axis 1 east-west) and the
// offset of its cycle.
struct SignalizedIntersection {
  std::string id;  // "signal_03"
  geometry::Vec2 position{0, 0};
  double heading[2] = {0.0, 0.0};  // direction of each axis' street at the node (rad)
  double width[2] = {0.0, 0.0};    // right-of-way of each axis' street (m)
  double offset = 0.0;             // the cycle starts at t = offset (s, in [0, cycle))
};

// The fixed-time signal plan of every signalised intersection (cycle: axis 0 protected left,
// green, yellow, all-red, then the same for axis 1). Pedestrians cross an axis' street while the
// other axis has green.
struct SignalPlan {
  double left = 7.0;
  double green = 15.0;
  double yellow = 4.0;
  double all_red = 2.0;
  double sidewalk = 3.0;  // sidewalk width: crosswalks run on the cross street's sidewalk band
  std::vector<SignalizedIntersection> intersections;

  double cycle() const { return 2.0 * (left + green + yellow + all_red); }
  // The phase of `axis` (0 or 1) at intersection i at time t.
  SignalState state(const SignalizedIntersection& i, int axis, double t) const;
};

// The ambient cars and crowd of a city scenario taken from a traffic episode file that a batch
// shares (scenario/city_traffic.h): the scenario's t = 0 is the episode's t = offset. The cars
// named in `withheld` are not part of the scenario: they would come near one of its own cars
// (scenario/traffic_clearance.h). In memory the others are also the last entities
// (pedestrian_ids.size() pedestrians, then the cars not withheld, in order); simConfigJson()
// writes them inline, and a batch writes this reference instead.
struct TrafficEpisodeRef {
  std::string file;  // relative to the directory of sim_config.json
  int episode = 0;
  double offset = 0.0;
  std::string sha256;                       // of the file's bytes, lowercase hex
  std::vector<std::string> car_ids;         // the entity id of each of the episode's cars, in order
  std::vector<std::string> pedestrian_ids;  // and of each of its pedestrians
  std::vector<std::string> withheld;        // car ids left out of the scenario, in car order
  std::shared_ptr<const std::string> text;  // the file's bytes (set by the generator)
  // Set by generateScenario(..., traffic_by_reference): only the pedestrians who stand (in order)
  // are in memory, as the last `lean` entities (the scene's groups and occluders count them);
  // the others are only named here, so the scenario is written by reference only.
  std::optional<std::size_t> lean;

  // How many of the last entities the reference stands for.
  std::size_t entityCount() const {
    return lean ? *lean : pedestrian_ids.size() + car_ids.size() - withheld.size();
  }
};

struct SimConfig {
  std::string scenario_id;
  ScenarioClass cls = ScenarioClass::kAreaSearch;
  std::uint64_t seed = 0;
  double duration = 0.0;
  WorldParams world;
  std::uint64_t world_fingerprint = 0;
  std::vector<ScenarioEntity> entities;
  std::vector<Group> groups;
  std::vector<Aircraft> aircraft;  // avoid only; written only when there are any
  Environment environment;
  UavSpec uav;
  Perturbations perturbations;
  std::optional<SpecProvenance> spec;  // written only for scenarios generated from a spec
  std::optional<SignalPlan> signals;   // the city's signal plan; absent in the suburb
  std::optional<TrafficEpisodeRef> traffic;  // city only: where the ambient traffic comes from
};

struct Scenario {
  Mission mission;
  SimConfig sim;
};

}  // namespace hameritt::scenario
