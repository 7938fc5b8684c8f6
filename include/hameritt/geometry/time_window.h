#pragma once
// Time windows: no-earlier-than (NET) and no-later-than (NLT) bounds, both optional.

#include <optional>

namespace hameritt::geometry {

// A closed interval [net, nlt] of mission time; a missing bound is open on that side, so an
// empty window is always active. Used by areas of interest and keep-out zones.
struct TimeWindow {
  std::optional<double> net;
  std::optional<double> nlt;

  // True when t lies inside the window (bounds inclusive).
  bool active(double t) const;
  // True when net <= nlt (or a bound is missing) and both are finite.
  bool valid() const;
  // True when neither bound is set (always active).
  bool unbounded() const { return !net && !nlt; }
  // True when the window and [t0, t1] share at least one instant.
  bool overlaps(double t0, double t1) const;
};

}  // namespace hameritt::geometry
