#include "hameritt/planning/request_checks.h"

#include <cmath>

#include "hameritt/scenario/error.h"

namespace hameritt::planning {

std::string checkPoint(const geometry::Vec3& p, const std::string& field) {
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(p[a])) {
      return field + "." + std::string(1, "xyz"[a]) + ": expected a finite coordinate (m), got " +
             scenario::formatNumber(p[a]);
    }
  }
  return "";
}

std::string checkWaypoints(const std::vector<geometry::Vec3>& points, const std::string& field,
                           std::size_t max_count) {
  if (points.empty()) return field + ": expected at least one waypoint (the goal), got none";
  if (points.size() > max_count) {
    return field + ": expected at most " + std::to_string(max_count) + " waypoints, got " +
           std::to_string(points.size());
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::string error = checkPoint(points[i], field + "[" + std::to_string(i) + "]");
    if (!error.empty()) return error;
  }
  return "";
}

}  // namespace hameritt::planning
