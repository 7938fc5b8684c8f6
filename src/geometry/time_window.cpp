#include "hameritt/geometry/time_window.h"

#include <cmath>

namespace hameritt::geometry {

// A NaN instant is never inside a window, not even an unbounded one.
bool TimeWindow::active(double t) const {
  if (std::isnan(t)) return false;
  if (net && !(t >= *net)) return false;
  if (nlt && !(t <= *nlt)) return false;
  return true;
}

bool TimeWindow::valid() const {
  if (net && !std::isfinite(*net)) return false;
  if (nlt && !std::isfinite(*nlt)) return false;
  return !(net && nlt) || *net <= *nlt;
}

// [t0, t1] with t0 > t1 (or a NaN end) is empty and overlaps nothing; so is an inverted window.
bool TimeWindow::overlaps(double t0, double t1) const {
  if (!(t0 <= t1)) return false;
  if (net && nlt && !(*net <= *nlt)) return false;
  if (net && !(t1 >= *net)) return false;
  if (nlt && !(t0 <= *nlt)) return false;
  return true;
}

}  // namespace hameritt::geometry
