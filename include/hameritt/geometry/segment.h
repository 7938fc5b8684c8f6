#pragma once
// Segments and polylines in the plane.

#include <optional>
#include <vector>

#include "hameritt/geometry/types.h"

namespace hameritt::geometry {

// Distance from point p to the closed segment [a, b]; a zero-length segment is a point.
double pointSegmentDistance(const Vec2& p, const Vec2& a, const Vec2& b);
// Closest point to p on the closed segment [a, b].
Vec2 closestPointOnSegment(const Vec2& p, const Vec2& a, const Vec2& b);
// True when the closed segments [a, b] and [c, d] share at least one point (touching counts;
// collinear overlap counts; zero-length segments behave as points).
bool segmentsIntersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);
// Minimum distance between two closed segments (0 when they intersect).
double segmentSegmentDistance(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);
// Proper crossing point of two segments, if they cross at a single point.
std::optional<Vec2> segmentIntersectionPoint(const Vec2& a, const Vec2& b, const Vec2& c,
                                             const Vec2& d);

// Total length of a polyline.
double polylineLength(const std::vector<Vec2>& pts);
// Point at arc length s along a polyline (clamped to [0, length]).
Vec2 polylinePointAt(const std::vector<Vec2>& pts, double s);
// Distance from p to the nearest point of a polyline (a single point is allowed).
double pointPolylineDistance(const Vec2& p, const std::vector<Vec2>& pts);

}  // namespace hameritt::geometry
