#pragma once
// Closed intervals of a scalar (mission time, or a segment parameter) and their union.

#include <stdexcept>
#include <string>
#include <vector>

namespace hameritt::adk {

// Bad input to an ADK core object (a sample out of order, a non-finite value): the caller's
// mistake, with a message that names the sample or field. Nodes catch it and log; the
// command-line tools exit with code 2.
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// A closed interval [lo, hi] with lo <= hi; lo == hi is a single instant (a touch).
struct Interval {
  double lo = 0.0;
  double hi = 0.0;
  double length() const { return hi - lo; }
};

// Intersection of two intervals; lo > hi when they are disjoint.
inline Interval intersect(const Interval& a, const Interval& b) {
  return {a.lo > b.lo ? a.lo : b.lo, a.hi < b.hi ? a.hi : b.hi};
}

// A union of closed intervals kept sorted and disjoint: intervals that overlap or touch
// merge. Used for the time a target is in view (each sighting covers one frame period).
class IntervalUnion {
 public:
  // Adds [lo, hi] (lo <= hi, both finite; InputError otherwise).
  void add(double lo, double hi);
  // Total length.
  double measure() const;
  const std::vector<Interval>& intervals() const { return intervals_; }
  bool empty() const { return intervals_.empty(); }

 private:
  std::vector<Interval> intervals_;
};

}  // namespace hameritt::adk
