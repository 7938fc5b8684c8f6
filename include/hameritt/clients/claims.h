#pragma once
// At most one claim per candidate location: a client tells the ADK "I see the target here" once,
// not at every frame. ROS-free.

#include <vector>

#include "hameritt/geometry/types.h"

namespace hameritt::clients {

// Remembers where claims were made. A new claim within `radius` metres (in the plane) of an
// earlier one is a repeat until `hold` seconds have passed since that earlier claim (hold <= 0:
// forever).
class ClaimLedger {
 public:
  ClaimLedger(double radius = 4.0, double hold = 30.0);

  // True (and recorded) when a claim at p, time t, is new; false for a repeat.
  bool claim(const geometry::Vec3& p, double t);
  // True when a claim at p, time t, would be a repeat (nothing recorded).
  bool isRepeat(const geometry::Vec3& p, double t) const;
  // Distinct locations claimed so far.
  std::size_t locations() const;

 private:
  struct Claim {
    geometry::Vec3 p;
    double t;
  };
  double radius_, hold_;
  std::vector<Claim> claims_;
  std::vector<geometry::Vec3> places_;
};

}  // namespace hameritt::clients
