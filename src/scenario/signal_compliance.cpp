// Signal compliance of the mission's own vehicles in the city: the entries of a car's front into
// the signalised intersection boxes, and the trajectory retimed with waits at the stop lines.

#include "hameritt/scenario/signal_compliance.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hameritt/geometry/types.h"
#include "hameritt/scenario/entity.h"

namespace hameritt::scenario {

using geometry::Vec2;

namespace {

constexpr double kNear = 60.0;        // intersections farther than this from the front are skipped
constexpr double kTurnClose = 4.0;    // a turn starts no later than this before its arrow ends
constexpr double kStopBack = 1.0;     // the front waits this far short of the box (m)
constexpr double kMinGap = 2.0;       // standstill bumper gap behind the lead (m)
constexpr double kScanStep = 0.1;     // s
constexpr double kWaitStep = 0.1;     // waits are multiples of this (s)
constexpr double kMaxSpeed = 30.0;    // no car drives faster (m/s)
constexpr double kEntryMargin = 0.2;  // the signal must allow the entry this long around it (s)

Vec2 unitOf(double a) { return {std::cos(a), std::sin(a)}; }

Vec2 frontOf(const TrajectoryPoint& q, double half) {
  return Vec2(q.x, q.y) + half * unitOf(q.yaw);
}

bool inBox(const SignalizedIntersection& si, const SignalPlan& plan, int axis, const Vec2& p) {
  const Vec2 u = unitOf(si.heading[axis]), d = p - si.position;
  const double along = d.dot(u), across = u.x() * d.y() - u.y() * d.x();
  return std::abs(along) < 0.5 * si.width[1 - axis] + plan.sidewalk &&
         std::abs(across) < 0.5 * si.width[axis];
}

bool inEither(const SignalizedIntersection& si, const SignalPlan& plan, const Vec2& p) {
  return inBox(si, plan, 0, p) || inBox(si, plan, 1, p);
}

// Time since the start of `axis`' protected arrow at si (in [0, cycle)).
double arrowPhase(const SignalPlan& plan, const SignalizedIntersection& si, int axis, double t) {
  const double c = plan.cycle();
  double tau = std::fmod(t - si.offset - (axis == 1 ? 0.5 * c : 0.0), c);
  if (tau < 0) tau += c;
  return tau;
}

bool judgedAllowed(const SignalPlan& plan, const SignalizedIntersection& si, int axis, double t,
                   double turned) {
  const SignalState st = plan.state(si, axis, t);
  const bool arrow = st == SignalState::kLeftArrow;
  if (std::abs(turned) <= 0.25 * geometry::kPi) {
    return st == SignalState::kGreen || st == SignalState::kYellow;
  }
  if (turned > 0) return arrow;
  return arrow || plan.state(si, 1 - axis, t) == SignalState::kLeftArrow;
}

// The stricter rule a retimed car follows at t: straight on only on green; a turn in the first
// part of an arrow that lets it go.
bool mayGo(const SignalPlan& plan, const SignalizedIntersection& si, int axis, double t,
           double turned) {
  if (std::abs(turned) <= 0.25 * geometry::kPi) {
    return plan.state(si, axis, t) == SignalState::kGreen;
  }
  for (int a = 0; a < 2; ++a) {
    if (a != axis && turned > 0) continue;
    if (plan.state(si, a, t) == SignalState::kLeftArrow &&
        arrowPhase(plan, si, a, t) <= plan.left - kTurnClose)
      return true;
  }
  return false;
}

// The heading change between t and the moment the front leaves si's boxes again.
double turnedAt(const Trajectory& tr, double half, const SignalizedIntersection& si,
                const SignalPlan& plan, double t, double dt) {
  const double yaw = sampleTrajectory(tr, t).yaw;
  double yaw_out = yaw;
  for (double u = t + dt; u <= tr.back().t + dt; u += dt) {
    const TrajectoryPoint q = sampleTrajectory(tr, u);
    yaw_out = q.yaw;
    if (!inEither(si, plan, frontOf(q, half))) break;
  }
  return geometry::wrapPi(yaw_out - yaw);
}

// The axis along which the front enters si at pose q, or -1.
int entryAxis(const SignalizedIntersection& si, const SignalPlan& plan, const Vec2& front,
              double yaw) {
  for (int axis = 0; axis < 2; ++axis) {
    if (inBox(si, plan, axis, front) && std::abs(std::cos(yaw - si.heading[axis])) >= 0.9)
      return axis;
  }
  return -1;
}

// The axis along which a front at `front` (heading `yaw`) enters si's box at this sample, having
// been outside it at the previous one (*was_in), or -1; *was_in becomes whether it is inside.
int entering(const SignalizedIntersection& si, const SignalPlan& plan, const Vec2& front,
             double yaw, char* was_in) {
  if ((front - si.position).squaredNorm() > kNear * kNear) {
    *was_in = 0;
    return -1;
  }
  const bool in = inEither(si, plan, front);
  const int axis = !*was_in && in ? entryAxis(si, plan, front, yaw) : -1;
  *was_in = in;
  return axis;
}

TrajectoryPoint rounded(TrajectoryPoint q) {
  q.t = roundMilli(q.t);
  q.x = roundMilli(q.x);
  q.y = roundMilli(q.y);
  q.z = roundMilli(q.z);
  q.yaw = roundMilli(q.yaw);
  return q;
}

// Makes the car stand still in `tr` at its pose of time `at` for `wait` seconds: the samples
// before `at` stay, those at it give way to the standing pair, and the later ones move `wait`
// later (in place: a wait costs a pass over the samples after it, not a copy of all of them).
void addWait(Trajectory* tr, double at, double wait) {
  TrajectoryPoint p = rounded(sampleTrajectory(*tr, at));
  p.t = roundMilli(at);
  TrajectoryPoint held = p;
  held.t = roundMilli(p.t + wait);
  const auto by_t = [](const TrajectoryPoint& q, double t) { return q.t < t; };
  const auto t_by = [](double t, const TrajectoryPoint& q) { return t < q.t; };
  // [i0, i1): the samples within 1e-9 s of the wait's start (the times are increasing).
  const auto i0 = std::lower_bound(tr->begin(), tr->end(), p.t - 1e-9, by_t) - tr->begin();
  const auto i1 = std::upper_bound(tr->begin() + i0, tr->end(), p.t + 1e-9, t_by) - tr->begin();
  for (auto it = tr->begin() + i1; it != tr->end(); ++it) it->t = roundMilli(it->t + wait);
  if (i1 - i0 >= 2) {
    tr->erase(tr->begin() + i0 + 2, tr->begin() + i1);
  } else {
    tr->insert(tr->begin() + i0, static_cast<std::size_t>(2 - (i1 - i0)), p);
  }
  (*tr)[static_cast<std::size_t>(i0)] = p;
  (*tr)[static_cast<std::size_t>(i0) + 1] = held;
}

// The latest time before `t` at which the car's centre stood `back` metres (along its path)
// short of its position at t, or the trajectory's start.
double timeBack(const Trajectory& tr, double t, double back) {
  TrajectoryPoint prev = sampleTrajectory(tr, t);
  double run = 0.0;
  for (double u = t - kScanStep; u > tr.front().t; u -= kScanStep) {
    const TrajectoryPoint q = sampleTrajectory(tr, u);
    run += std::hypot(prev.x - q.x, prev.y - q.y);
    prev = q;
    if (run >= back) return u;
  }
  return tr.front().t;
}

// Whether the lead stands in the follower's way at t: ahead in its lane, heading the same way,
// closer than the standstill gap.
bool blockedBy(const TrajectoryPoint& q, const Trajectory& lead, double t, double need) {
  const TrajectoryPoint l = sampleTrajectory(lead, t);
  const Vec2 u = unitOf(q.yaw), d(l.x - q.x, l.y - q.y);
  const double along = d.dot(u), across = u.x() * d.y() - u.y() * d.x();
  return along > 0 && along < need && std::abs(across) < 1.5 && std::cos(l.yaw - q.yaw) > 0.5;
}

}  // namespace

std::vector<SignalEntry> signalEntries(const Trajectory& traj, double length,
                                       const SignalPlan& plan, double dt) {
  std::vector<SignalEntry> out;
  if (traj.empty() || plan.intersections.empty() || !(dt > 0)) return out;
  const double half = 0.5 * length;
  std::vector<char> was_in(plan.intersections.size(), 0);
  const double t0 = traj.front().t, t1 = traj.back().t;
  const auto n = static_cast<long>(std::floor((t1 - t0) / dt + 1e-9));
  for (long k = 0; k <= n; ++k) {
    const double t = t0 + static_cast<double>(k) * dt;
    const TrajectoryPoint q = sampleTrajectory(traj, t);
    const Vec2 front = frontOf(q, half);
    for (std::size_t i = 0; i < plan.intersections.size(); ++i) {
      const auto& si = plan.intersections[i];
      const int axis = entering(si, plan, front, q.yaw, &was_in[i]);
      if (axis < 0) continue;
      SignalEntry e;
      e.intersection = i;
      e.axis = axis;
      e.t = t;
      e.turned = turnedAt(traj, half, si, plan, t, dt);
      e.state = plan.state(si, axis, t);
      e.allowed = judgedAllowed(plan, si, axis, t, e.turned);
      out.push_back(e);
    }
  }
  return out;
}

std::string describeEntry(const SignalEntry& e, const SignalPlan& plan) {
  const bool turning = std::abs(e.turned) > 0.25 * geometry::kPi;
  char buf[200];
  std::snprintf(buf, sizeof(buf), "enters %s on %s at t = %.2f s (axis %d, %s)",
                plan.intersections.at(e.intersection).id.c_str(), toString(e.state), e.t, e.axis,
                !turning       ? "going straight on"
                : e.turned > 0 ? "turning left"
                               : "turning right");
  return buf;
}

Trajectory obeySignals(const Trajectory& traj, double length, const SignalPlan& plan,
                       const Trajectory* lead, double lead_length) {
  if (traj.size() < 2 || (plan.intersections.empty() && !lead)) return traj;
  Trajectory tr = traj;
  const double half = 0.5 * length;
  const double need = 0.5 * (length + lead_length) + kMinGap;
  std::vector<char> was_in(plan.intersections.size(), 0);
  // The intersections' positions side by side: most scan steps find every one far.
  std::vector<Vec2> at;
  at.reserve(plan.intersections.size());
  for (const auto& si : plan.intersections) at.push_back(si.position);
  const double horizon = 2.0 * plan.cycle() + 1.0;
  double t = tr.front().t;
  for (int guard = 0; t <= tr.back().t + 1e-9 && guard < 200000; ++guard) {
    const TrajectoryPoint q = sampleTrajectory(tr, t);
    if (lead && blockedBy(q, *lead, t, need)) {
      // Wait where the car stood a step earlier until the lead has moved on.
      const double at = std::max(tr.front().t, t - kScanStep);
      const TrajectoryPoint p = sampleTrajectory(tr, at);
      double wait = kWaitStep;
      while (wait < 600.0 && blockedBy(p, *lead, at + wait, need + 0.5)) wait += kWaitStep;
      addWait(&tr, at, wait);
      t = roundMilli(at + wait) + kScanStep;
      continue;
    }
    const Vec2 front = frontOf(q, half);
    if (!lead) {
      // Far from every intersection: on to the first step at which the front may be near one.
      double nearest = 1e18;
      for (const Vec2& p : at) nearest = std::min(nearest, (front - p).squaredNorm());
      nearest = std::sqrt(nearest);
      if (nearest > kNear + kMaxSpeed * kScanStep) {
        std::fill(was_in.begin(), was_in.end(), 0);
        t += kScanStep * std::floor((nearest - kNear) / (kMaxSpeed * kScanStep));
        continue;
      }
    }
    bool waited = false;
    for (std::size_t i = 0; i < plan.intersections.size() && !waited; ++i) {
      if ((front - at[i]).squaredNorm() > kNear * kNear) {
        was_in[i] = 0;  // entering()'s answer for a far front
        continue;
      }
      const auto& si = plan.intersections[i];
      const int axis = entering(si, plan, front, q.yaw, &was_in[i]);
      if (axis < 0) continue;
      const double turned = turnedAt(tr, half, si, plan, t, kScanStep);
      // The front crosses into the box between t - step and t; it may go when the rule holds
      // over that interval and a margin around it.
      auto fine = [&](double shift) {
        for (double u = t - kScanStep - kEntryMargin; u <= t + kEntryMargin + 1e-9; u += 0.05)
          if (!mayGo(plan, si, axis, u + shift, turned)) return false;
        return true;
      };
      if (fine(0.0)) continue;
      double wait = kWaitStep;
      while (wait <= horizon && !fine(wait)) wait += kWaitStep;
      if (wait > horizon) continue;  // no time lets it go (no arrow long enough to turn)
      const double at = timeBack(tr, t - kScanStep, kStopBack);
      addWait(&tr, at, wait);
      t = roundMilli(at + wait);  // rescanned from the wait's end: the front is outside
      waited = true;
    }
    if (!waited) t += kScanStep;
  }
  return tr;
}

}  // namespace hameritt::scenario
