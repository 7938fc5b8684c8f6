#include "world_entities.h"

#include <cmath>

#include "hameritt/scenario/catalog.h"

namespace hameritt::scenario::world_entities {

using geometry::Vec2;
using geometry::Vec3;

namespace {
Vec3 roundVec(const Vec3& v) { return {roundMilli(v.x()), roundMilli(v.y()), roundMilli(v.z())}; }
}  // namespace

int appendEntity(std::vector<Entity>* entities, EntityCounters* counters, EntityClass cls,
                 const std::string& prefix, const Vec3& bottom, double yaw, const Vec3& size,
                 Attributes attrs, int block) {
  Entity e;
  int& counter = counters->next[static_cast<int>(cls)];
  e.id = prefix + "_" + std::to_string(++counter);
  e.cls = cls;
  e.attributes = std::move(attrs);
  e.box = boxFromPose(roundVec(bottom), roundMilli(geometry::wrapPi(yaw)), roundVec(size));
  e.block = block;
  entities->push_back(std::move(e));
  return static_cast<int>(entities->size()) - 1;
}

void parkCars(Rng& rng, double driveway_probability, double kerb_probability,
              std::vector<ParkingSlot>* slots, std::vector<Entity>* entities,
              EntityCounters* counters) {
  for (auto& s : *slots) {
    const double p = s.driveway ? driveway_probability : kerb_probability;
    if (!rng.bernoulli(p)) continue;
    const auto& model = catalog::pickModel(rng);
    Attributes a;
    a.set("vehicle_class", model.vehicle_class);
    a.set("make", model.make);
    a.set("model", model.model);
    a.set("color", catalog::pick(rng, catalog::carColors()));
    s.occupant = appendEntity(entities, counters, EntityClass::kCar, "car",
                              Vec3(s.position.x(), s.position.y(), s.ground_z), s.yaw,
                              Vec3(model.length, model.width, model.height), a, s.block);
  }
}

void addKerbSlots(const std::vector<StreetNode>& nodes, const std::vector<StreetEdge>& edges,
                  const std::vector<Block>& blocks, const geometry::OccluderIndex& keep_clear,
                  double clear_radius, double spacing,
                  const std::function<double(const StreetEdge&)>& clearance,
                  std::vector<ParkingSlot>* slots) {
  for (int ei = 0; ei < static_cast<int>(edges.size()); ++ei) {
    const auto& e = edges[ei];
    const double end = clearance(e);
    if (end < 0) continue;
    const Vec2 a = nodes[e.a].position, b = nodes[e.b].position;
    const double len = (b - a).norm();
    const Vec2 u = (b - a) / len;
    const Vec2 n(-u.y(), u.x());
    for (int side = -1; side <= 1; side += 2) {
      const double offset = 0.5 * e.width - 1.05;
      // Right-hand traffic: cars on the right of the travel direction face along it.
      const double yaw = side < 0 ? std::atan2(u.y(), u.x()) : std::atan2(-u.y(), -u.x());
      for (double s = end; s < len - end; s += spacing) {
        const Vec2 c = a + s * u + side * offset * n;
        if (!keep_clear.near(c, clear_radius).empty()) continue;
        ParkingSlot slot;
        slot.position = Vec2(roundMilli(c.x()), roundMilli(c.y()));
        slot.yaw = roundMilli(geometry::wrapPi(yaw));
        slot.ground_z = 0.0;
        slot.edge = ei;
        const Vec2 probe = c + side * (0.5 * e.width + 3.0) * n;
        slot.block = -1;
        for (const auto& bl : blocks) {
          if (bl.outline.contains(probe)) slot.block = bl.index;
        }
        slots->push_back(slot);
      }
    }
  }
}

}  // namespace hameritt::scenario::world_entities
