#include "hameritt/adk/clock_watchdog.h"

#include <cmath>

#include "hameritt/adk/intervals.h"
#include "hameritt/scenario/error.h"

namespace hameritt::adk {

ClockWatchdog::ClockWatchdog(double timeout, double late_after)
    : timeout_(timeout), late_after_(late_after) {
  if (!(timeout >= 0 && std::isfinite(timeout))) {
    throw InputError("clock timeout: expected wall seconds >= 0 (0 = off), got " +
                     scenario::formatNumber(timeout));
  }
}

void ClockWatchdog::clock(double sim_t, double wall) {
  if (!seen_) {
    seen_ = true;
    if (sim_t > late_after_) late_start_ = sim_t;
  }
  if (sim_t > 0 && (!started_ || sim_t > last_sim_)) {
    started_ = true;
    last_sim_ = sim_t;
    last_wall_ = wall;
  }
}

std::string ClockWatchdog::stalled(double wall) const {
  if (timeout_ == 0 || !started_ || wall - last_wall_ < timeout_) return "";
  char buf[200];
  std::snprintf(buf, sizeof(buf),
                "sim time stopped at %.3f s: no new /clock for %.1f wall s (simulator dead or "
                "stalled)",
                last_sim_, wall - last_wall_);
  return buf;
}

}  // namespace hameritt::adk
