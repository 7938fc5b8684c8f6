#include "hameritt/planning/uav_planner.h"

#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/datastructures/NearestNeighborsLinear.h>
#include <ompl/datastructures/NearestNeighborsSqrtApprox.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/rng.h"
#include "ompl_glue.h"

namespace hameritt::planning {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using geometry::Vec3;

namespace detail {

namespace {
std::once_flag g_silence_once;
}

void silenceOmplOnce() {
  std::call_once(g_silence_once, [] { ompl::msg::setLogLevel(ompl::msg::LOG_NONE); });
}

}  // namespace detail

void setOmplLogging(bool enabled) {
  detail::silenceOmplOnce();
  ompl::msg::setLogLevel(enabled ? ompl::msg::LOG_INFO : ompl::msg::LOG_NONE);
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Output paths are rounded to 1e-3; they are validated with the margin reduced by this.
constexpr double kValidationSlack = 2e-3;

// RRT-Connect and RRT* with their (otherwise process-seeded) RNG re-seeded per plan.
class SeededRrtConnect : public og::RRTConnect {
 public:
  SeededRrtConnect(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::RRTConnect(si) {
    rng_.setLocalSeed(seed);
  }
};
class SeededRrtStar : public og::RRTstar {
 public:
  SeededRrtStar(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::RRTstar(si) {
    rng_.setLocalSeed(seed);
  }
};

Vec3 vec(const ob::State* s) {
  const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
  return {v->values[0], v->values[1], v->values[2]};
}

double pointSegmentDistance3(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double l2 = d.squaredNorm();
  const double u = l2 > 0 ? std::clamp((p - a).dot(d) / l2, 0.0, 1.0) : 0.0;
  return (a + d * u - p).norm();
}

// Keep-out zones are checked against the interval of times at which the path may reach a point:
// from the straight-line lower bound to that plus `horizon`.
struct TimeModel {
  const WorldValidity* v;
  Vec3 start;
  double t0;
  double vmax;
  double horizon;
  bool point(const Vec3& p) const {
    if (!v->staticValid(p)) return false;
    const double lo = t0 + (p - start).norm() / vmax;
    return v->kozClear(p, lo, lo + horizon);
  }
  bool segment(const Vec3& a, const Vec3& b) const {
    if (!v->staticSegmentValid(a, b)) return false;
    const double lo = t0 + pointSegmentDistance3(start, a, b) / vmax;
    const double hi = t0 + std::max((a - start).norm(), (b - start).norm()) / vmax + horizon;
    return v->kozSegmentClearDuring(a, b, lo, hi);
  }
};

Vec3 pointAt(const std::vector<Vec3>& p, const std::vector<double>& cum, double s,
             std::size_t* seg) {
  std::size_t i =
      static_cast<std::size_t>(std::upper_bound(cum.begin(), cum.end(), s) - cum.begin());
  i = std::clamp<std::size_t>(i, 1, p.size() - 1) - 1;
  *seg = i;
  const double l = cum[i + 1] - cum[i];
  const double u = l > 0 ? (s - cum[i]) / l : 0.0;
  return p[i] + (p[i + 1] - p[i]) * std::clamp(u, 0.0, 1.0);
}

// Greedy vertex shortcutting, then random partial shortcuts between points anywhere on the path
// (Geraerts & Overmars 2007, "Creating high-quality paths for motion planning"), then greedy
// again. Every new segment is checked with the planner's own exact predicate.
std::vector<Vec3> shortcut(std::vector<Vec3> p, const TimeModel& tm, int iterations,
                           std::uint64_t seed) {
  auto greedy = [&](const std::vector<Vec3>& in) {
    std::vector<Vec3> out{in.front()};
    std::size_t i = 0;
    while (i + 1 < in.size()) {
      std::size_t j = in.size() - 1;
      while (j > i + 1 && !tm.segment(in[i], in[j])) --j;
      out.push_back(in[j]);
      i = j;
    }
    return out;
  };
  if (p.size() < 3) return p;
  p = greedy(p);
  scenario::Rng rng(seed);
  for (int it = 0; it < iterations && p.size() >= 3; ++it) {
    std::vector<double> cum(p.size(), 0.0);
    for (std::size_t i = 1; i < p.size(); ++i) cum[i] = cum[i - 1] + (p[i] - p[i - 1]).norm();
    double s0 = rng.uniform(0.0, cum.back()), s1 = rng.uniform(0.0, cum.back());
    if (s0 > s1) std::swap(s0, s1);
    std::size_t i0, i1;
    const Vec3 a = pointAt(p, cum, s0, &i0), b = pointAt(p, cum, s1, &i1);
    if (i0 == i1) continue;  // same segment: nothing to gain
    const double old_len = s1 - s0;
    if ((b - a).norm() >= old_len - 1e-6) continue;
    if (!tm.segment(a, b)) continue;
    std::vector<Vec3> q(p.begin(), p.begin() + static_cast<long>(i0) + 1);
    if ((a - q.back()).norm() > 1e-6) q.push_back(a);
    if ((b - p[i1 + 1]).norm() > 1e-6) q.push_back(b);
    q.insert(q.end(), p.begin() + static_cast<long>(i1) + 1, p.end());
    p = std::move(q);
  }
  return greedy(p);
}

struct Attempt {
  PlanStatus status = PlanStatus::kNoSolution;
  std::vector<Vec3> path;
  long iterations = 0;
  std::string message;
};

// R^3 without the default projection that RealVectorStateSpace registers at setup (a random
// linear map with cell sizes estimated from sampled states): only projection-based planners
// (KPIECE, SBL, ...) use it, not RRT-Connect or RRT*, and it was a tenth of a plan's set-up.
class UnprojectedSpace : public ob::RealVectorStateSpace {
 public:
  UnprojectedSpace() : ob::RealVectorStateSpace(3) {}
  void registerProjections() override {}
};

Attempt runOmpl(const WorldValidity& validity, const TimeModel& tm, const Vec3& start,
                const Vec3& goal, const UavPlannerSettings& st, std::uint64_t seed,
                std::chrono::steady_clock::time_point deadline) {
  auto space = std::make_shared<UnprojectedSpace>();
  ob::RealVectorBounds bounds(3);
  const auto& b = validity.bounds();
  bounds.setLow(0, b.min.x());
  bounds.setHigh(0, b.max.x());
  bounds.setLow(1, b.min.y());
  bounds.setHigh(1, b.max.y());
  bounds.setLow(2, validity.settings().altitude_min);
  bounds.setHigh(2, validity.settings().altitude_max);
  space->setBounds(bounds);
  // The planner's sampler is the second one allocated (the default projection's set-up took
  // the first, when there was one): its stream is kept.
  space->setStateSamplerAllocator(detail::rngSamplerAllocator(scenario::deriveSeed(seed, 1), 1));
  auto si = std::make_shared<ob::SpaceInformation>(space);
  si->setStateValidityChecker([&tm](const ob::State* s) { return tm.point(vec(s)); });
  si->setMotionValidator(std::make_shared<detail::PredicateMotionValidator>(
      si.get(),
      [&tm](const ob::State* a, const ob::State* c) { return tm.segment(vec(a), vec(c)); }));
  si->setup();

  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  ob::ScopedState<ob::RealVectorStateSpace> s(space), g(space);
  for (int i = 0; i < 3; ++i) {
    s[i] = start[i];
    g[i] = goal[i];
  }
  pdef->setStartAndGoalStates(s, g, 1e-6);
  pdef->setOptimizationObjective(std::make_shared<ob::PathLengthOptimizationObjective>(si));

  const auto seed32 = static_cast<std::uint32_t>(scenario::deriveSeed(seed, 2) & 0xffffffffu);
  ob::PlannerPtr planner;
  long budget = st.max_iterations;
  if (st.algorithm == UavAlgorithm::kRrtConnect) {
    auto p = std::make_shared<SeededRrtConnect>(si, seed32);
    p->setRange(st.range);
    p->setNearestNeighbors<ompl::NearestNeighborsSqrtApprox>();
    planner = p;
  } else {
    auto p = std::make_shared<SeededRrtStar>(si, seed32);
    p->setRange(st.range);
    p->setGoalBias(st.goal_bias);
    p->setNearestNeighbors<ompl::NearestNeighborsLinear>();
    planner = p;
    budget = st.rrtstar_iterations;
  }
  planner->setProblemDefinition(pdef);
  planner->setup();

  Attempt out;
  bool wall = false;
  long calls = 0;
  ob::PlannerTerminationCondition ptc([&] {
    ++calls;
    if (calls > budget) return true;
    if ((calls & 63) == 0 && std::chrono::steady_clock::now() > deadline) {
      wall = true;
      return true;
    }
    return false;
  });
  planner->solve(ptc);
  out.iterations = std::min(calls, budget);
  const bool exact = pdef->hasExactSolution();
  const bool approx = pdef->hasApproximateSolution();
  if (exact || (approx && st.accept_approximate)) {
    const auto& path = *pdef->getSolutionPath()->as<og::PathGeometric>();
    for (std::size_t i = 0; i < path.getStateCount(); ++i)
      out.path.push_back(vec(path.getState(i)));
    out.status = exact ? PlanStatus::kExact : PlanStatus::kApproximate;
    if (!exact)
      out.message = "approximate: ends " + scenario::formatNumber((out.path.back() - goal).norm()) +
                    " m from the goal";
  } else if (wall) {
    out.status = PlanStatus::kTimeout;
    out.message =
        "no path within the time limit of " + scenario::formatNumber(st.time_limit) + " s";
  } else {
    out.status = PlanStatus::kNoSolution;
    out.message = "no path found within " + std::to_string(budget) + " iterations";
  }
  return out;
}

}  // namespace

const char* toString(PlanStatus s) {
  switch (s) {
    case PlanStatus::kExact:
      return "exact";
    case PlanStatus::kApproximate:
      return "approximate";
    case PlanStatus::kNoSolution:
      return "no_solution";
    case PlanStatus::kInvalidStart:
      return "invalid_start";
    case PlanStatus::kInvalidGoal:
      return "invalid_goal";
    case PlanStatus::kTimeout:
      return "timeout";
  }
  return "unknown";
}

void UavPlannerSettings::validate() const {
  auto bad = [](const char* field, const std::string& what, double v) {
    throw scenario::ConfigError(std::string("planning.") + field + ": expected " + what + ", got " +
                                scenario::formatNumber(v));
  };
  if (!(range > 0 && std::isfinite(range)))
    bad("range", "a positive finite distance in metres", range);
  if (!(goal_bias >= 0 && goal_bias <= 1)) bad("goal_bias", "a probability in [0, 1]", goal_bias);
  if (!(time_limit > 0 && time_limit <= 3600))
    bad("time_limit", "seconds in (0, 3600]", time_limit);
  if (max_iterations < 1) bad("max_iterations", "an integer >= 1", max_iterations);
  if (rrtstar_iterations < 1) bad("rrtstar_iterations", "an integer >= 1", rrtstar_iterations);
  if (shortcut_iterations < 0) bad("shortcut_iterations", "an integer >= 0", shortcut_iterations);
  if (!(sample_spacing >= 0.01 && sample_spacing <= 100)) {
    bad("sample_spacing", "metres in [0.01, 100]", sample_spacing);
  }
  speed.validate();
}

PlanResult planUavPath(const WorldValidity& validity, const Vec3& start, const Vec3& goal,
                       double t0, const UavPlannerSettings& settings, std::uint64_t seed) {
  settings.validate();
  if (!std::isfinite(t0)) throw scenario::ConfigError("planning.t0: expected a finite time");
  detail::silenceOmplOnce();
  const auto began = std::chrono::steady_clock::now();
  const auto deadline = began + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>(settings.time_limit));
  PlanResult r;
  auto finish = [&]() {
    r.planning_time =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    return r;
  };
  const double vmax = std::hypot(settings.speed.max_speed,
                                 std::max(settings.speed.climb_rate, settings.speed.descent_rate));
  if (!validity.staticValid(start) || !validity.kozClear(start, t0, t0)) {
    r.status = PlanStatus::kInvalidStart;
    r.message = "start " + validity.explain(start, t0);
    if (validity.explain(start, t0).empty()) r.message = "start is invalid";
    return finish();
  }
  // The UAV holds the goal after arrival: a zone covering it that is active at any time after
  // the earliest possible arrival makes it invalid.
  const double t_goal = t0 + (goal - start).norm() / vmax;
  if (!validity.staticValid(goal) || !validity.kozClear(goal, t_goal, kInf)) {
    r.status = PlanStatus::kInvalidGoal;
    std::string why = validity.explain(goal, t_goal);
    if (why.empty()) {
      why = "goal lies in a keep-out zone active after the earliest arrival at t = " +
            scenario::formatNumber(t_goal);
    }
    r.message = "goal " + why;
    return finish();
  }
  std::vector<double> horizons{kInf};
  if (validity.hasTimedKozs()) horizons = {20.0, 120.0, kInf};
  std::string last_failure;
  for (std::size_t k = 0; k < horizons.size(); ++k) {
    const TimeModel tm{&validity, start, t0, vmax, horizons[k]};
    const std::uint64_t aseed = scenario::deriveSeed(seed, 100 + k);
    Attempt a;
    if ((goal - start).norm() < 1e-9) {
      a.status = PlanStatus::kExact;
      a.path = {start};
    } else if (tm.segment(start, goal)) {
      a.status = PlanStatus::kExact;
      a.path = {start, goal};
    } else {
      a = runOmpl(validity, tm, start, goal, settings, aseed, deadline);
    }
    r.iterations += a.iterations;
    if (a.status == PlanStatus::kTimeout) {
      r.status = a.status;
      r.message = a.message;
      return finish();
    }
    if (a.status != PlanStatus::kExact && a.status != PlanStatus::kApproximate) {
      last_failure = a.message;
      continue;
    }
    std::vector<Vec3> geo =
        shortcut(a.path, tm, settings.shortcut_iterations, scenario::deriveSeed(aseed, 7));
    scenario::Trajectory traj = timeParameterize(geo, t0, settings.speed, settings.sample_spacing);
    const std::string err = validity.checkTrajectory(traj, 0.25, kValidationSlack);
    if (!err.empty()) {
      last_failure = "time-parameterized path rejected: " + err;
      continue;
    }
    r.status = a.status;
    r.message = a.status == PlanStatus::kExact ? "exact solution" : a.message;
    r.path = std::move(traj);
    r.length = pathLength(geo);
    return finish();
  }
  r.status = PlanStatus::kNoSolution;
  r.message = last_failure;
  return finish();
}

PlanResult planUavWaypoints(const WorldValidity& validity, const std::vector<Vec3>& waypoints,
                            double t0, const UavPlannerSettings& settings, std::uint64_t seed) {
  if (waypoints.size() < 2) {
    throw scenario::ConfigError("planning.waypoints: expected at least 2 waypoints, got " +
                                std::to_string(waypoints.size()));
  }
  PlanResult all;
  all.status = PlanStatus::kExact;
  all.message = "exact solution";
  double t = t0;
  for (std::size_t i = 0; i + 1 < waypoints.size(); ++i) {
    PlanResult leg = planUavPath(validity, waypoints[i], waypoints[i + 1], t, settings,
                                 scenario::deriveSeed(seed, i));
    all.iterations += leg.iterations;
    all.planning_time += leg.planning_time;
    if (leg.status != PlanStatus::kExact) {
      all.status = leg.status == PlanStatus::kApproximate ? PlanStatus::kApproximate : leg.status;
      all.message = "leg " + std::to_string(i) + ": " + leg.message;
      if (leg.status != PlanStatus::kApproximate) {
        all.path.clear();
        return all;
      }
    }
    std::size_t from = all.path.empty() ? 0 : 1;
    for (std::size_t k = from; k < leg.path.size(); ++k) all.path.push_back(leg.path[k]);
    all.length += leg.length;
    t = all.path.back().t;
    if (leg.status == PlanStatus::kApproximate) break;
  }
  return all;
}

}  // namespace hameritt::planning
