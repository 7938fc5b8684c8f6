#pragma once
// Mission metrics: what a run achieved (targets found, when), what it cost (path, flight time,
// energy) and what it broke (keep-out violations), with coverage of the areas of interest, and
// the mission lifecycle that decides the outcome. Written as metrics.json. ROS-free.

#include <optional>
#include <string>
#include <vector>

#include "hameritt/adk/avoid_score.h"
#include "hameritt/adk/constraint_monitor.h"
#include "hameritt/adk/coverage.h"
#include "hameritt/adk/detection_scoring.h"
#include "hameritt/adk/follow_score.h"
#include "hameritt/adk/intervals.h"
#include "hameritt/adk/track_score.h"
#include "hameritt/geometry/types.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::adk {

// Electrical-power estimate of a multirotor from its motion, from momentum (actuator-disk)
// theory: a rotor of disk area A producing thrust T needs the induced power
// T^(3/2) / sqrt(2 rho A) (Leishman, Principles of Helicopter Aerodynamics, 2nd ed., ch. 2),
// divided by the figure of merit for the profile and motor losses. The thrust is the one the
// measured acceleration needs, T = m |a + g z|, shared by the rotors; a parasitic drag term
// 1/2 rho CdA |v|^3 is added. The thrust is capped at max_thrust_to_weight x m g, what the
// rotors can give, so that a jump in the odometry (a teleport, a reset) cannot claim unbounded
// power. The induced-power saving of forward flight (translational lift)
// is neglected, so the estimate errs high at speed. Landed (not airborne), the power is 0.
// Defaults: the Sentinel-class quadrotor of models/sentinel.urdf (1.04 kg, four 5-inch props
// of radius 0.0635 m): about 154 W hovering.
struct EnergyModel {
  double mass = 1.04;          // kg
  double gravity = 9.81;       // m/s^2
  double air_density = 1.225;  // kg/m^3 (ISA sea level)
  int rotors = 4;
  double rotor_radius = 0.0635;  // m
  double figure_of_merit = 0.6;  // induced / total rotor power
  double drag_area = 0.02;       // Cd x frontal area, m^2
  double max_thrust_to_weight = 3.0;
  double airborne_altitude = 0.3;  // m above ground: above it the UAV is flying
  double moving_speed = 0.2;       // m/s: faster than this it is flying, whatever its height

  // Throws scenario::ConfigError naming "energy.<field>" and the bad value.
  void validate() const;
  // Power hovering (a = 0, v = 0), W.
  double hoverPower() const;
  // Power with velocity v and acceleration a (world frame), W.
  double power(const geometry::Vec3& v, const geometry::Vec3& a) const;
  bool airborne(const geometry::Vec3& p, const geometry::Vec3& v) const;
};

enum class Outcome { kSuccess, kTimeout, kCrashed, kAborted, kEnded, kFailed };
// "success", "timeout", "crashed", "aborted", "ended" (the simulator stopped at its duration
// before the time limit), "failed" (the objective was reached but a criterion of its phase was
// broken on the way: an avoid mission that lost separation, a follow phase that failed).
const char* toString(Outcome o);

// How the objective is judged.
struct ObjectiveSettings {
  // A target counts as found when the ADK's perfect perception sees it (maneuver-only runs,
  // where the maneuver is what is evaluated), instead of by a correct detection claim.
  bool found_by_sighting = false;
  // Track objectives: each target must be in view (a camera box with enough visible pixels)
  // for at least this fraction of the mission time; judged at the time limit.
  double track_fraction = 0.5;
  // Throws scenario::ConfigError naming "objective.<field>".
  void validate() const;
};

struct TargetMetrics {
  std::string id;
  bool found = false;                        // by the rule of ObjectiveSettings
  std::optional<double> first_correct_time;  // stamp of the first correct detection claim
  std::optional<double> first_seen_time;     // stamp of the first perfect-perception sighting
  double in_view_time = 0.0;                 // seconds in some camera's view
};

struct DetectionCounts {
  int total = 0;
  int correct = 0;                  // verdict target (repeats included)
  int false_on_confusers = 0;       // verdict confuser
  int false_on_other_entities = 0;  // verdict other
  int false_on_nothing = 0;         // verdict none
};

struct FlightMetrics {
  double path_length = 0.0;  // m, over every sample
  double flight_time = 0.0;  // s airborne
  double energy = 0.0;       // J, EnergyModel
  double max_speed = 0.0;    // m/s
};

struct MissionMetrics {
  std::string scenario_id;
  std::string scenario_class;
  std::string objective_type;
  std::string mode;
  Outcome outcome = Outcome::kAborted;
  std::string reason;
  double start_time = 0.0;  // mission time the ADK started judging
  double end_time = 0.0;
  double time_limit = 0.0;
  std::vector<TargetMetrics> targets;
  std::optional<double> time_to_first_correct;  // earliest correct detection of any target
  std::optional<double> time_to_all_found;      // when the last target was found
  DetectionCounts detections;
  std::vector<Violation> violations;
  double violation_duration = 0.0;
  FlightMetrics flight;
  EnergyModel energy_model;
  double coverage_cell_size = 0.0;
  std::vector<AoiCoverage> coverage;
  std::vector<AoiStatus> aoi_time;
  double prior_weighted_coverage = 0.0;
  std::optional<AvoidScore> avoid;  // missions with an avoid phase
  std::optional<FollowPhaseScore> follow;  // missions with a follow phase
  std::optional<TrackPhaseScore> track;    // missions with a track phase
};

// Collects the figures of one run.
class MetricsAccumulator {
 public:
  MetricsAccumulator(const scenario::Mission& mission, const ObjectiveSettings& objective = {},
                     const EnergyModel& energy = {});

  // A state of the UAV (odometry): mission time, position, world-frame velocity. Samples not
  // after the previous one are ignored (false); non-finite values are an InputError.
  bool addState(double t, const geometry::Vec3& p, const geometry::Vec3& v);
  // A scored detection claim.
  void addVerdict(double stamp, const DetectionVerdict& verdict);
  // An entity seen by a camera at `stamp` (perfect perception); the view is taken to last one
  // frame period (1 / camera rate).
  void addSighting(const std::string& entity_id, double stamp, double frame_period);

  // True when the objective is met at mission time t: find: every target found; track: every
  // target in view for track_fraction of t (t > 0).
  bool objectiveMet(double t) const;
  // Find objectives can end early; track objectives are judged at the time limit.
  bool isTrack() const { return track_; }
  const FlightMetrics& flight() const { return flight_; }
  const std::vector<TargetMetrics>& targets() const { return targets_; }

  MissionMetrics finish(Outcome outcome, const std::string& reason, double start_time,
                        double end_time, double time_limit, const std::string& mode,
                        const ConstraintMonitor& monitor, const CoverageGrid& coverage) const;

 private:
  TargetMetrics* target(const std::string& id);
  std::string scenario_id_, scenario_class_, objective_type_;
  ObjectiveSettings objective_;
  EnergyModel energy_;
  bool track_ = false;
  std::vector<TargetMetrics> targets_;
  std::vector<IntervalUnion> in_view_;
  DetectionCounts counts_;
  FlightMetrics flight_;
  bool have_state_ = false;
  double last_t_ = 0.0;
  geometry::Vec3 last_p_{0, 0, 0}, last_v_{0, 0, 0};
  double last_power_ = 0.0;
  bool last_airborne_ = false;
};

// metrics.json: a fixed field order (docs/reference/formats.md), absent times as null.
std::string metricsJson(const MissionMetrics& m);
// Writes metrics.json atomically (temporary file and rename); OutputError naming the path.
void writeMetricsJson(const MissionMetrics& m, const std::string& path);

// The states of a mission run, and the transitions the ADK node drives.
enum class MissionState {
  kWaiting,
  kRunning,
  kSucceeded,
  kTimeout,
  kCrashed,
  kAborted,
  kEnded,
  kFailed
};
// "waiting", "running", "succeeded", "timeout", "crashed", "aborted", "ended", "failed".
const char* toString(MissionState s);
Outcome outcomeOf(MissionState s);

// waiting -> running at the first sim time > 0 with odometry; running -> succeeded (objective
// met), timeout (time limit reached), crashed; any state before an end -> aborted, or ended (the
// simulation stopped at its duration). An ended mission stays ended.
class MissionLifecycle {
 public:
  // time_limit in seconds of mission time (> 0, finite; InputError otherwise).
  explicit MissionLifecycle(double time_limit);

  // Sim time t with or without odometry so far. Returns true when the state changed.
  bool update(double t, bool have_odometry);
  bool succeed(double t, const std::string& reason);
  bool crash(double t, const std::string& reason);
  // The objective reached with a phase criterion broken (Outcome::kFailed).
  bool fail(double t, const std::string& reason);
  bool abort(double t, const std::string& reason);
  // The simulator stopped at its duration at sim time t (before the time limit).
  bool simulationEnded(double t, const std::string& reason);

  MissionState state() const { return state_; }
  bool ended() const;
  double timeLimit() const { return time_limit_; }
  double startTime() const { return start_; }
  double endTime() const { return end_; }
  const std::string& reason() const { return reason_; }

 private:
  bool end(MissionState s, double t, const std::string& reason);
  double time_limit_;
  MissionState state_ = MissionState::kWaiting;
  double start_ = 0.0, end_ = 0.0;
  std::string reason_ = "waiting for sim time > 0 and odometry";
};

}  // namespace hameritt::adk
