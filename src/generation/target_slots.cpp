#include "hameritt/generation/target_slots.h"

#include <cmath>

namespace hameritt::scenario {

using geometry::Vec2;

bool insideBy20(const World& world, const Vec2& p) {
  const auto b = world.bounds();
  return p.x() > b.min.x() + 20 && p.x() < b.max.x() - 20 && p.y() > b.min.y() + 20 &&
         p.y() < b.max.y() - 20;
}

bool pursuitSlotFits(const World& world, const ParkingSlot& s) {
  if (s.block < 0 || !insideBy20(world, s.position)) return false;
  const auto& e = world.edges()[static_cast<std::size_t>(s.edge)];
  const Vec2 a = world.nodes()[e.a].position, b = world.nodes()[e.b].position;
  const Vec2 f(std::cos(s.yaw), std::sin(s.yaw));
  const Vec2 from = (b - a).dot(f) > 0 ? a : b;
  const double along = (s.position - from).dot(f);
  const double corner_clearance = 0.5 * world.params().street_width + 1.0;
  return along + kPullOut < (b - a).norm() - corner_clearance - 2.0;
}

bool targetSlotAllowed(const World& world, int slot, ScenarioClass cls) {
  const ParkingSlot& s = world.slots()[static_cast<std::size_t>(slot)];
  if (s.occupant >= 0) return false;
  switch (cls) {
    case ScenarioClass::kAreaSearch:
      return insideBy20(world, s.position);
    case ScenarioClass::kPursuit:
      return !s.driveway && pursuitSlotFits(world, s);
    case ScenarioClass::kRouteSearch:
      return false;
  }
  return false;
}

}  // namespace hameritt::scenario
