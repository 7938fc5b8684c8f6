#include "hameritt/planning/follow.h"

#include <algorithm>

namespace hameritt::planning {

double clearCarrotTime(const WorldValidity& validity, const scenario::Trajectory& path,
                       const geometry::Vec3& here, double plan_t, double lookahead,
                       double clearance) {
  const double slack = std::max(0.0, validity.settings().margin - clearance);
  for (const double f : {1.0, 0.75, 0.5, 0.25}) {
    const double t = plan_t + lookahead * f;
    const scenario::TrajectoryPoint p = scenario::sampleTrajectory(path, t);
    if (validity.obstacleSegmentClear(here, geometry::Vec3(p.x, p.y, p.z), slack)) return t;
  }
  return plan_t + lookahead * 0.125;
}

}  // namespace hameritt::planning
