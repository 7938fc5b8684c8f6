#pragma once
// Line of sight against the static scene, accelerated by a uniform grid over the plane.

#include <cstdint>
#include <utility>
#include <vector>

#include "hameritt/geometry/oriented_box.h"

namespace hameritt::geometry {

// A set of occluding boxes (buildings, garages, fences, tree canopies, parked cars) indexed by
// a uniform grid so that a sight line only tests the boxes near it.
class OccluderIndex {
 public:
  // cell: grid cell size in metres (> 0).
  explicit OccluderIndex(double cell = 20.0);

  // Adds a box and returns its index (0, 1, 2, ... in insertion order). Throws GeometryError
  // for a box with a non-positive or non-finite size.
  int add(const OrientedBox& box);
  std::size_t size() const { return boxes_.size(); }
  const OrientedBox& box(int i) const { return boxes_.at(static_cast<std::size_t>(i)); }
  // std::cos and std::sin of box(i)'s yaw (after build()).
  const std::pair<double, double>& trig(int i) const {
    return trig_.at(static_cast<std::size_t>(i));
  }

  // Builds the grid; must be called after the last add() and before any query (queries on a
  // stale index throw std::logic_error). Const queries are then safe from many threads.
  void build();

  // True when no box other than those in `ignore` touches the 3D segment [a, b].
  bool clear(const Vec3& a, const Vec3& b, const std::vector<int>& ignore = {}) const;
  // 2D variant: true when no footprint other than those in `ignore` touches the segment.
  bool clear2(const Vec2& a, const Vec2& b, const std::vector<int>& ignore = {}) const;
  // Index of every box whose footprint comes within `radius` of p (exact footprint test),
  // in ascending order.
  std::vector<int> near(const Vec2& p, double radius) const;
  // Index of every box whose footprint's bounding rectangle overlaps `area`, ascending.
  std::vector<int> candidates(const Aabb2& area) const;

 private:
  std::int64_t key(int ix, int iy) const;
  void cellRange(const Aabb2& b, int* x0, int* y0, int* x1, int* y1) const;

  double cell_;
  std::vector<OrientedBox> boxes_;
  std::vector<Aabb2> bounds_;
  // Per box: std::cos and std::sin of its yaw (filled by build()).
  std::vector<std::pair<double, double>> trig_;
  // Sorted (cell key, box index) pairs; kept flat for speed and determinism.
  std::vector<std::pair<std::int64_t, int>> cells_;
  bool dirty_ = false;
  void requireBuilt() const;
};

}  // namespace hameritt::geometry
