#pragma once

#include <string>

namespace hameritt::adk {

// Notices a dead or stalled simulator: once sim time has passed 0, sim time that does not
// advance for `timeout` wall seconds. Also notices a late start: a first sim time already past
// `late_after` seconds (the ADK was started, or restarted, in a mission under way).
class ClockWatchdog {
 public:
  // timeout: wall seconds (0 = never stalls; < 0 or non-finite: InputError).
  explicit ClockWatchdog(double timeout, double late_after = 1.0);

  // A sim time read at wall time `wall` (seconds of any steady clock).
  void clock(double sim_t, double wall);
  // At wall time `wall`: "" while the clock is alive (or not started), else why it is not.
  std::string stalled(double wall) const;
  // The first sim time read when it was past late_after, else a negative number.
  double lateStart() const { return late_start_; }

 private:
  double timeout_, late_after_;
  bool started_ = false, seen_ = false;
  double last_sim_ = 0.0, last_wall_ = 0.0, late_start_ = -1.0;
};

}  // namespace hameritt::adk
