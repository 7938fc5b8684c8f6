// A spec's keep-out zones (specKozPolygons): apart from the generator, which plans with OMPL, so
// that the spec checker (and its fuzz target) can recompute them.
#include <algorithm>
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

}  // namespace

std::vector<Polygon> specKozPolygons(const World& world, const ScenarioPlan::Koz& koz,
                                     const OrientedBox& target) {
  std::vector<Polygon> out;
  if (koz.over == "target") {
    out.push_back(roundedPolygon(
        geometry::orientedRectangle(target.center2(), koz.size, koz.size, target.yaw)));
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
