#pragma once
// Oriented 3D bounding boxes: yaw-only rotation about +z (objects stand upright).

#include <array>

#include "hameritt/geometry/polygon.h"
#include "hameritt/geometry/types.h"

namespace hameritt::geometry {

// Box with centre, full size (length along the heading, width across it, height) and yaw.
struct OrientedBox {
  Vec3 center{0, 0, 0};
  Vec3 size{0, 0, 0};  // length (body x), width (body y), height (z)
  double yaw = 0.0;

  double minZ() const { return center.z() - 0.5 * size.z(); }
  double maxZ() const { return center.z() + 0.5 * size.z(); }
  Vec2 center2() const { return center.head<2>(); }
  // The four footprint corners, counter-clockwise: body (-l/2,-w/2), (+l/2,-w/2),
  // (+l/2,+w/2), (-l/2,+w/2), rotated by yaw and moved to the centre.
  std::array<Vec2, 4> corners2() const;
  // The same corners with the yaw's cosine and sine given (std::cos(yaw), std::sin(yaw)).
  std::array<Vec2, 4> corners2(double cos_yaw, double sin_yaw) const;
  // Footprint as a counter-clockwise polygon.
  Polygon footprint() const;
  Aabb2 bounds2() const;
  // Point containment (boundary counts as inside).
  bool contains(const Vec3& p) const;
  // The same test with the yaw's cosine and sine given (std::cos(yaw), std::sin(yaw)).
  bool contains(const Vec3& p, double cos_yaw, double sin_yaw) const;
  // True when the closed 3D segment [a, b] touches the box (slab test in the box frame).
  bool intersectsSegment(const Vec3& a, const Vec3& b) const;
  // The same test with the yaw's cosine and sine given (they must be std::cos(yaw) and
  // std::sin(yaw)), for callers that keep them per box.
  bool intersectsSegment(const Vec3& a, const Vec3& b, double cos_yaw, double sin_yaw) const;
  // Converts a world point into the box's body frame (origin at the centre).
  Vec3 toBody(const Vec3& p) const;
};

// Minimum distance between two boxes' footprints in the plane (0 when they overlap).
double footprintDistance(const OrientedBox& a, const OrientedBox& b);
// The same distance with b's yaw cosine and sine given (std::cos(b.yaw), std::sin(b.yaw)).
double footprintDistance(const OrientedBox& a, const OrientedBox& b, double cos_b, double sin_b);
// True when the two footprints overlap in the plane (touching counts).
bool footprintsOverlap(const OrientedBox& a, const OrientedBox& b);

}  // namespace hameritt::geometry
