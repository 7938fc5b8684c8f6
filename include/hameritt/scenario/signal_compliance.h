#pragma once
// How a vehicle of the mission meets the signals of a city's plan: the entries of its front into
// the signalised intersection boxes with the signal its axis shows then, and the same trajectory
// retimed so that it waits at the stop line until the signal lets it go (the rule the ambient
// cars of scenario/city_traffic.h follow).

#include <cstddef>
#include <string>
#include <vector>

#include "hameritt/scenario/scenario.h"

namespace hameritt::scenario {

// One entry of a car's front into an intersection box (the carriageway of `axis` from the far
// side of the crosswalk before the cross street to that after it), from outside both streets'
// boxes, running along the axis. turned: the heading's change when the front leaves the box
// again (a turn beyond 45 degrees: positive left, negative right). allowed: a car going
// straight on may enter on green or yellow, a left turn on its axis' arrow, a right turn on
// either street's arrow.
struct SignalEntry {
  std::size_t intersection = 0;  // index into plan.intersections
  int axis = 0;
  double t = 0.0;
  double turned = 0.0;
  SignalState state = SignalState::kRed;  // the axis' signal at t
  bool allowed = true;
};

// Every entry of a car of length `length` moving along `traj`, sampled every `dt` seconds over
// the trajectory's times.
std::vector<SignalEntry> signalEntries(const Trajectory& traj, double length,
                                       const SignalPlan& plan, double dt = 0.05);

// "enters signal_03 on red at t = 41.2 s (axis 0, going straight on)".
std::string describeEntry(const SignalEntry& e, const SignalPlan& plan);

// `traj` retimed so that the car obeys `plan`: where its front would enter a box when it may
// not (a car going straight on: green only, so that it clears the box on yellow; a turning car:
// the first `plan.left` less 4 s of its arrow, for a right turn also of the cross street's
// arrow), it stops with its front 1 m short of the box and waits until it may. With `lead` (the
// car it follows, of length `lead_length`), it also waits while the lead stands less than the
// standstill gap of 2 m ahead of it in its lane. The path is unchanged; each wait delays the
// rest. Times and positions are rounded to the millimetre.
Trajectory obeySignals(const Trajectory& traj, double length, const SignalPlan& plan,
                       const Trajectory* lead = nullptr, double lead_length = 0.0);

}  // namespace hameritt::scenario
