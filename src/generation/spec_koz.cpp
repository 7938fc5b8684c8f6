// A spec's keep-out zones (specKozPolygons): apart from the generator, which plans with OMPL, so
// that the spec checker (and its fuzz target) can recompute them.
#include <algorithm>
#include <cmath>
#include <utility>

#include "hameritt/generation/generator.h"
#include "hameritt/scenario/entity.h"

namespace hameritt::scenario {

using geometry::OrientedBox;
using geometry::Polygon;
using geometry::Vec2;

namespace {

// Vertices rounded to the millimetre, as the generator writes every polygon.
Polygon roundedPolygon(const Polygon& p) {
  std::vector<Vec2> v;
  for (const auto& q : p.vertices()) v.emplace_back(roundMilli(q.x()), roundMilli(q.y()));
  return Polygon(v);
}

// A convex polygon grown by `margin` on every side (each edge moved out, corners mitred).
Polygon grownConvex(const Polygon& p, double margin) {
  const auto& v = p.vertices();
  const std::size_t n = v.size();
  if (n < 3 || margin <= 0) return p;
  double area2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& a = v[i];
    const Vec2& b = v[(i + 1) % n];
    area2 += a.x() * b.y() - b.x() * a.y();
  }
  const double side = area2 > 0 ? 1.0 : -1.0;  // counter-clockwise: outward is to the right
  auto normal = [&](std::size_t i) -> Vec2 {
    const Vec2 d = (v[(i + 1) % n] - v[i]).normalized();
    return Vec2(d.y(), -d.x()) * side;
  };
  std::vector<Vec2> out;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 n0 = normal((i + n - 1) % n), n1 = normal(i);
    // The corner where the two moved edges meet: x . n0 = v . n0 + m, x . n1 = v . n1 + m.
    const double det = n0.x() * n1.y() - n0.y() * n1.x();
    if (std::abs(det) < 1e-9) {
      out.push_back(v[i] + n1 * margin);
      continue;
    }
    const double c0 = v[i].dot(n0) + margin, c1 = v[i].dot(n1) + margin;
    out.emplace_back((c0 * n1.y() - c1 * n0.y()) / det, (n0.x() * c1 - n1.x() * c0) / det);
  }
  return Polygon(out);
}

// The street segment nearest to p: its index, or -1 when the world has none.
int nearestStreet(const World& world, const Vec2& p, double* along) {
  int best = -1;
  double best_d = 0;
  for (int i = 0; i < static_cast<int>(world.edges().size()); ++i) {
    const StreetEdge& e = world.edges()[static_cast<std::size_t>(i)];
    const Vec2& a = world.nodes()[static_cast<std::size_t>(e.a)].position;
    const Vec2& b = world.nodes()[static_cast<std::size_t>(e.b)].position;
    const double len = (b - a).norm();
    if (len < 1e-9) continue;
    const double s = std::clamp((p - a).dot(b - a) / len, 0.0, len);
    const double d = (a + (b - a) * (s / len) - p).norm();
    if (best < 0 || d < best_d - 1e-9) {
      best = i;
      best_d = d;
      *along = s;
    }
  }
  return best;
}

}  // namespace

std::vector<Polygon> specKozPolygons(const World& world, const ScenarioPlan::Koz& koz,
                                     const OrientedBox& target,
                                     const std::vector<AreaOfInterest>& aois) {
  std::vector<Polygon> out;
  const Vec2 c = target.center2();
  if (koz.over == "target") {
    out.push_back(roundedPolygon(geometry::orientedRectangle(c, koz.size, koz.size, target.yaw)));
    return out;
  }
  if (koz.over == "block") {
    // The block whose outline holds the target, else the nearest one.
    int best = world.blockAt(c);
    double best_d = 0;
    const bool inside = best >= 0;
    for (const auto& b : world.blocks()) {
      if (inside) break;
      const double d = b.outline.distance(c);
      if (best < 0 || d < best_d - 1e-9) {
        best = b.index;
        best_d = d;
      }
    }
    if (best >= 0) {
      out.push_back(roundedPolygon(
          grownConvex(world.blocks()[static_cast<std::size_t>(best)].interior, koz.margin)));
    }
    return out;
  }
  if (koz.over == "street") {
    double along = 0;
    const int i = nearestStreet(world, c, &along);
    if (i < 0) return out;
    const StreetEdge& e = world.edges()[static_cast<std::size_t>(i)];
    const Vec2& a = world.nodes()[static_cast<std::size_t>(e.a)].position;
    const Vec2 d = (world.nodes()[static_cast<std::size_t>(e.b)].position - a).normalized();
    out.push_back(roundedPolygon(geometry::orientedRectangle(
        a + d * along, koz.length, e.width + 2 * koz.margin, std::atan2(d.y(), d.x()))));
    return out;
  }
  if (koz.over == "aoi") {
    if (koz.aoi >= 1 && koz.aoi <= static_cast<int>(aois.size())) {
      out.push_back(roundedPolygon(
          grownConvex(aois[static_cast<std::size_t>(koz.aoi - 1)].polygon, koz.margin)));
    }
    return out;
  }
  EntityClass cls;
  if (!parseEntityClass(koz.over, &cls)) return out;
  std::vector<std::pair<double, int>> near;
  for (int i = 0; i < static_cast<int>(world.entities().size()); ++i) {
    const Entity& e = world.entities()[static_cast<std::size_t>(i)];
    if (e.cls == cls) near.emplace_back((e.box.center2() - target.center2()).norm(), i);
  }
  std::sort(near.begin(), near.end());
  for (std::size_t k = 0; k < near.size() && static_cast<int>(k) < koz.count; ++k) {
    const Entity& e = world.entities()[static_cast<std::size_t>(near[k].second)];
    out.push_back(
        roundedPolygon(geometry::orientedRectangle(e.box.center2(), e.box.size.x() + 2 * koz.margin,
                                                   e.box.size.y() + 2 * koz.margin, e.box.yaw)));
  }
  return out;
}

}  // namespace hameritt::scenario
