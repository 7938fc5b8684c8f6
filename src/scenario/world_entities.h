#pragma once
// Shared by the world builders (world.cpp, city_world.cpp): appending entities with
// per-class numbered ids and millimetre-rounded boxes, and parking random catalog cars in
// parking slots.

#include <functional>
#include <string>
#include <vector>

#include "hameritt/geometry/line_of_sight.h"
#include "hameritt/scenario/entity.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario::world_entities {

// Per-class counters of the ids handed out ("house_1", "house_2", ...).
struct EntityCounters {
  int next[32] = {};
};

// Appends an entity "<prefix>_<n>" (n counts per class from 1) whose box has its bottom centre
// at `bottom`, heading `yaw` and size `size`, every value rounded to millimetres (milliradians);
// returns its index.
int appendEntity(std::vector<Entity>* entities, EntityCounters* counters, EntityClass cls,
                 const std::string& prefix, const geometry::Vec3& bottom, double yaw,
                 const geometry::Vec3& size, Attributes attrs, int block);

// Parks a random catalog car (make, model, colour) in each slot with probability
// `driveway_probability` (off-street slots) or `kerb_probability`, setting the slot's occupant.
void parkCars(Rng& rng, double driveway_probability, double kerb_probability,
              std::vector<ParkingSlot>* slots, std::vector<Entity>* entities,
              EntityCounters* counters);

// Kerb parking slots every `spacing` m on both sides of each street edge, from `clearance(edge)`
// metres after its first node to as far before its last (a negative clearance skips the edge),
// `kerb_inset` m in from the kerb, skipping spots within `clear_radius` of a box of
// `keep_clear`. A slot faces the travel direction of its side (right-hand traffic) and belongs
// to the block its kerb borders (or -1).
void addKerbSlots(const std::vector<StreetNode>& nodes, const std::vector<StreetEdge>& edges,
                  const std::vector<Block>& blocks, const geometry::OccluderIndex& keep_clear,
                  double clear_radius, double spacing,
                  const std::function<double(const StreetEdge&)>& clearance,
                  std::vector<ParkingSlot>* slots);

}  // namespace hameritt::scenario::world_entities
