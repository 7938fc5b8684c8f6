#include "hameritt/adk/intervals.h"

#include <algorithm>
#include <cmath>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {

void IntervalUnion::add(double lo, double hi) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) {
    throw InputError("interval [" + scenario::formatNumber(lo) + ", " + scenario::formatNumber(hi) +
                     "]: expected finite bounds with lo <= hi");
  }
  // First interval that ends at or after lo: everything before it stays as it is.
  auto it = std::lower_bound(intervals_.begin(), intervals_.end(), lo,
                             [](const Interval& i, double v) { return i.hi < v; });
  Interval merged{lo, hi};
  auto last = it;
  while (last != intervals_.end() && last->lo <= merged.hi) {
    merged.lo = std::min(merged.lo, last->lo);
    merged.hi = std::max(merged.hi, last->hi);
    ++last;
  }
  it = intervals_.erase(it, last);
  intervals_.insert(it, merged);
}

double IntervalUnion::measure() const {
  double m = 0.0;
  for (const auto& i : intervals_) m += i.length();
  return m;
}

}  // namespace hameritt::adk
