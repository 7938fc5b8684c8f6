#pragma once
// UAV path planning on OMPL over the world's validity checker: RRT-Connect or RRT*, seeded and
// deterministic, shortcut-smoothed, time-parameterized and re-validated continuously with the
// keep-out zones' time windows.

#include <cstdint>
#include <string>
#include <vector>

#include "hameritt/geometry/types.h"
#include "hameritt/planning/time_parameterization.h"
#include "hameritt/planning/validity.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::planning {

// Outcome of a plan.
enum class PlanStatus {
  kExact,         // the path reaches the goal
  kApproximate,   // the path ends short of the goal (only when accept_approximate is set)
  kNoSolution,    // iteration budget spent without a valid path
  kInvalidStart,  // the start violates a hard constraint at the start time
  kInvalidGoal,   // the goal violates one (or lies in a zone active after the earliest arrival)
  kTimeout,       // the wall-clock safety limit stopped the planner
};
// "exact", "approximate", "no_solution", "invalid_start", "invalid_goal", "timeout".
const char* toString(PlanStatus s);

enum class UavAlgorithm {
  kRrtConnect,  // RRT-Connect (Kuffner & LaValle 2000): fast, feasible
  kRrtStar,     // RRT* (Karaman & Frazzoli 2011): asymptotically optimal, fixed iteration budget
};

// Planner settings. validate() throws scenario::ConfigError naming "planning.<field>".
struct UavPlannerSettings {
  UavAlgorithm algorithm = UavAlgorithm::kRrtConnect;
  double range = 80.0;       // longest tree extension, metres
  double goal_bias = 0.05;   // RRT* goal sampling probability, [0, 1]
  double time_limit = 2.0;   // wall-clock safety per plan, seconds (status kTimeout)
  int max_iterations = 20000;      // RRT-Connect iteration budget (deterministic termination)
  int rrtstar_iterations = 1500;   // RRT* runs exactly this many iterations
  int shortcut_iterations = 120;   // random partial shortcuts (Geraerts & Overmars 2007)
  double sample_spacing = 1.0;     // output samples at most this far apart, metres
  bool accept_approximate = false;
  SpeedLimits speed;
  void validate() const;
};

// Result of a plan: status, a human-readable message, and the timed path {t, x, y, z, yaw}
// (rounded to 1e-3, linear interpolation between samples; empty unless exact/approximate).
struct PlanResult {
  PlanStatus status = PlanStatus::kNoSolution;
  std::string message;
  scenario::Trajectory path;
  double planning_time = 0.0;  // seconds of wall clock (informational only)
  long iterations = 0;         // planner iterations over all attempts
  double length = 0.0;         // geometric path length, metres
  bool ok() const { return status == PlanStatus::kExact || status == PlanStatus::kApproximate; }
};

// Plans a flight from `start` (at time t0) to `goal`. Deterministic: the same inputs and seed
// give the same path bit for bit on any thread (OMPL's global RNG is never drawn from: states
// come from a scenario::Rng sampler seeded per call, nearest neighbours are deterministic and
// termination is by iteration count). Keep-out zones are checked at the time the path reaches
// each state: the planner bounds that time from below by straight-line distance over the top
// speed and, where zones have time windows, tries growing windows of uncertainty above it
// (20 s, 120 s, unbounded); the time-parameterized result is then checked exactly
// (WorldValidity::checkTrajectory, 0.25 m pieces) and the first attempt that passes is
// returned. Pipeline: RRT-Connect / RRT* -> greedy and random partial shortcutting
// (Geraerts & Overmars 2007) -> timeParameterize(). Throws ConfigError for bad settings.
PlanResult planUavPath(const WorldValidity& validity, const geometry::Vec3& start,
                       const geometry::Vec3& goal, double t0, const UavPlannerSettings& settings,
                       std::uint64_t seed);

// Global planner for a client's sparse waypoints: plans each leg with planUavPath (leg i seeded
// with scenario::deriveSeed(seed, i), starting when the previous leg ends, stopping at each
// waypoint) and concatenates them. The status is the first leg's failure, if any.
PlanResult planUavWaypoints(const WorldValidity& validity,
                            const std::vector<geometry::Vec3>& waypoints, double t0,
                            const UavPlannerSettings& settings, std::uint64_t seed);

// OMPL's console output is silenced the first time any planner runs; this turns it back on
// (true) or off again.
void setOmplLogging(bool enabled);

}  // namespace hameritt::planning
