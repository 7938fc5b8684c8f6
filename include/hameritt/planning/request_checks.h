#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "hameritt/geometry/types.h"

namespace hameritt::planning {

// The most waypoints one request may carry (a plan through more is refused, not attempted:
// each leg is a planning query).
constexpr std::size_t kMaxWaypoints = 1000;

// Checks one point: "" when every coordinate is finite, else e.g.
// "start.y: expected a finite coordinate (m), got nan".
std::string checkPoint(const geometry::Vec3& p, const std::string& field);

// Checks a request's waypoints: between 1 and max_count of them, every coordinate finite.
// Returns "" when they are acceptable, else an error naming the field, e.g.
// "waypoints[3].z: expected a finite coordinate (m), got nan".
std::string checkWaypoints(const std::vector<geometry::Vec3>& points, const std::string& field,
                           std::size_t max_count = kMaxWaypoints);

}  // namespace hameritt::planning
