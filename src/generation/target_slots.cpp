#include "hameritt/generation/target_slots.h"

#include <algorithm>
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

namespace {

double laneOffset(const World& world) {
  return 0.5 * world.params().street_width - kLaneOffsetFromKerb;
}
double cornerClearance(const World& world) { return 0.5 * world.params().street_width + 1.0; }

}  // namespace

TrajectoryPoint LaneDrive::pose(double s, double t) const {
  const Vec2 p = from + dir * s + Vec2(dir.y(), -dir.x()) * lane_offset;
  return {t, roundMilli(p.x()), roundMilli(p.y()), 0.0, roundMilli(std::atan2(dir.y(), dir.x()))};
}

std::vector<RouteStart> routeStarts(const World& world) {
  std::vector<RouteStart> out;
  for (const auto& e : world.edges()) {
    for (const int from : {e.a, e.b}) {
      const int to = from == e.a ? e.b : e.a;
      const double len = (world.nodes()[static_cast<std::size_t>(to)].position -
                          world.nodes()[static_cast<std::size_t>(from)].position)
                             .norm();
      for (double s = 20.0; s < 20.0 + 0.2 * len && s <= len - cornerClearance(world) - 2.0;
           s += 1.0) {
        out.push_back({from, to, s});
      }
    }
  }
  return out;
}

LaneDrive routeStartDrive(const World& world, const RouteStart& start) {
  LaneDrive d;
  const Vec2 a = world.nodes()[static_cast<std::size_t>(start.from)].position;
  const Vec2 b = world.nodes()[static_cast<std::size_t>(start.to)].position;
  const double len = (b - a).norm();
  d.from = a;
  d.dir = (b - a) / len;
  d.lane_offset = laneOffset(world);
  d.begin = start.s;
  d.end = len - std::min(cornerClearance(world), 0.45 * len);
  return d;
}

LaneDrive pursuitDrive(const World& world, int slot) {
  const ParkingSlot& s = world.slots()[static_cast<std::size_t>(slot)];
  const auto& e = world.edges()[static_cast<std::size_t>(s.edge)];
  const Vec2 pa = world.nodes()[e.a].position, pb = world.nodes()[e.b].position;
  const Vec2 fwd(std::cos(s.yaw), std::sin(s.yaw));
  const bool ab = (pb - pa).dot(fwd) > 0;
  LaneDrive d;
  d.from = ab ? pa : pb;
  d.dir = ((ab ? pb : pa) - d.from).normalized();
  d.lane_offset = laneOffset(world);
  d.begin = (s.position - d.from).dot(d.dir) + kPullOut;
  const double len = (pb - pa).norm();
  d.end = len - std::min(cornerClearance(world), 0.45 * len);
  return d;
}

bool targetSlotAllowed(const World& world, int slot, ScenarioClass cls) {
  const ParkingSlot& s = world.slots()[static_cast<std::size_t>(slot)];
  if (s.occupant >= 0) return false;
  switch (cls) {
    case ScenarioClass::kAreaSearch:
      return insideBy20(world, s.position);
    case ScenarioClass::kPursuit:
    case ScenarioClass::kFollow:
    case ScenarioClass::kTrack:
      return !s.driveway && pursuitSlotFits(world, s);
    case ScenarioClass::kRouteSearch:
    case ScenarioClass::kAvoid:
      return false;
  }
  return false;
}

}  // namespace hameritt::scenario
