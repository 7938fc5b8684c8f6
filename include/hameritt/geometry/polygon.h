#pragma once
// Simple polygons in the plane (ENU x/y), stored without repeating the first vertex.

#include <vector>

#include "hameritt/geometry/segment.h"
#include "hameritt/geometry/types.h"

namespace hameritt::geometry {

// Axis-aligned rectangle in the plane.
struct Aabb2 {
  Vec2 min{0, 0};
  Vec2 max{0, 0};
  bool overlaps(const Aabb2& o) const {
    return min.x() <= o.max.x() && o.min.x() <= max.x() && min.y() <= o.max.y() &&
           o.min.y() <= max.y();
  }
  bool contains(const Vec2& p) const {
    return p.x() >= min.x() && p.x() <= max.x() && p.y() >= min.y() && p.y() <= max.y();
  }
};

// A polygon given by its vertices in order (either orientation). The ring is implicitly closed:
// the last vertex connects back to the first. Areas of interest, keep-out zones, footprints.
class Polygon {
 public:
  Polygon() = default;
  explicit Polygon(std::vector<Vec2> vertices);

  const std::vector<Vec2>& vertices() const { return vertices_; }
  std::size_t size() const { return vertices_.size(); }

  // Signed area (shoelace): positive when counter-clockwise.
  double signedArea() const;
  double area() const;
  // Area centroid; for a degenerate (zero-area) polygon, the vertex mean.
  Vec2 centroid() const;
  Aabb2 bounds() const;
  double perimeter() const;

  // Point-in-polygon; points on the boundary (edges or vertices) count as inside. Non-zero
  // winding rule, so where a ring overlaps itself (a bufferPolyline hairpin) that is inside.
  bool contains(const Vec2& p) const;
  // Distance from p to the boundary ring.
  double boundaryDistance(const Vec2& p) const;
  // Distance from p to the polygon region (0 inside or on the boundary).
  double distance(const Vec2& p) const;
  // True when the closed segment [a, b] touches the polygon region (crosses an edge, touches
  // the boundary, or lies inside).
  bool intersectsSegment(const Vec2& a, const Vec2& b) const;
  // True when the polyline touches the polygon region anywhere.
  bool intersectsPolyline(const std::vector<Vec2>& pts) const;
  // True when the two polygon regions share at least one point.
  bool intersects(const Polygon& other) const;
  // Minimum distance between the two regions (0 when they intersect).
  double distance(const Polygon& other) const;

  // Simple: at least 3 vertices, finite coordinates, non-zero area, no repeated consecutive
  // vertex, and no two non-adjacent edges touching (a figure-eight or a spike is not simple).
  // An explicitly closed ring (last vertex equal to the first) repeats a vertex, so it is not
  // simple; a straight vertex in the middle of an edge is allowed.
  bool isSimple() const;
  // The same ring, counter-clockwise.
  Polygon counterClockwise() const;

 private:
  std::vector<Vec2> vertices_;
};

// Axis-aligned rectangle polygon, counter-clockwise from min corner.
Polygon rectangle(const Vec2& min, const Vec2& max);
// Rectangle of size (length along yaw, width across) centred at c, rotated by yaw,
// counter-clockwise.
Polygon orientedRectangle(const Vec2& c, double length, double width, double yaw);

// Buffers a polyline into a band polygon of total width `width` (half on each side) with
// mitred joins (bevelled where the mitre would exceed 2x the half-width) and flat ends.
// The result is counter-clockwise. Throws GeometryError for fewer than 2 distinct points or a
// non-positive width. Used for route search bands and street keep-out polygons. At hairpins,
// U-turns and segments shorter than the width the ring may overlap itself (see contains()).
Polygon bufferPolyline(const std::vector<Vec2>& polyline, double width);

}  // namespace hameritt::geometry
