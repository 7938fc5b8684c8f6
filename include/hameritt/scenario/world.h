#pragma once
// The procedurally generated suburban neighborhood: a street grid with jittered intersections,
// blocks of house lots (houses, detached garages, driveways, fences, trees), parked cars, and
// the parking slots and sidewalks that scenarios place their entities on. Deterministic by seed.

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "hameritt/geometry/line_of_sight.h"
#include "hameritt/geometry/polygon.h"
#include "hameritt/scenario/entity.h"

namespace hameritt::scenario {

// World generation parameters (config/world.json). Lengths in metres.
struct WorldParams {
  std::uint64_t seed = 1;
  double extent_x = 1000.0;  // east-west size, centred on the ENU origin
  double extent_y = 1000.0;  // north-south size
  double block_length_min = 180.0;  // spacing of north-south streets
  double block_length_max = 240.0;
  double block_depth_min = 110.0;  // spacing of east-west streets
  double block_depth_max = 150.0;
  double intersection_jitter = 6.0;
  double street_width = 10.0;
  double sidewalk_width = 2.0;
  double lot_frontage_min = 18.0;
  double lot_frontage_max = 26.0;
  double lot_depth = 34.0;
  double garage_probability = 0.8;
  double two_door_garage_probability = 0.4;
  double fence_probability = 0.6;
  double trees_per_lot_max = 3.0;
  double driveway_car_probability = 0.35;
  double street_parking_probability = 0.12;  // per street-side slot
  double driveway_height = 0.12;

  // Throws ConfigError naming the field and the bad value.
  void validate() const;
};

// An intersection of the street grid.
struct StreetNode {
  geometry::Vec2 position;
};

// A street segment between two intersections; `entity` indexes its street entity.
struct StreetEdge {
  int a = 0;
  int b = 0;
  double width = 0.0;
  std::string name;
  int entity = -1;
};

// A city block: the quadrilateral between four streets (`outline`, counter-clockwise, on the
// street centrelines), its buildable interior and the sidewalk ring around it.
struct Block {
  int index = 0;
  std::string name;  // "block_07"
  geometry::Polygon outline;
  geometry::Polygon interior;
  std::vector<geometry::Vec2> sidewalk;  // closed ring, last point == first point
};

// A place where a car can be parked: in front of a garage door or at the kerb.
struct ParkingSlot {
  geometry::Vec2 position;
  double yaw = 0.0;        // heading of a car parked there
  double ground_z = 0.0;   // surface height (driveway slab or street)
  bool driveway = false;
  int block = -1;          // block of the lot (driveways) or the block the kerb borders
  int edge = -1;           // street edge (kerb slots)
  int occupant = -1;       // world entity parked there, or -1 when free
};

// The static neighborhood. Immutable once generated; safe to share between threads.
class World {
 public:
  const WorldParams& params() const { return params_; }
  const std::vector<Entity>& entities() const { return entities_; }
  const std::vector<StreetNode>& nodes() const { return nodes_; }
  const std::vector<StreetEdge>& edges() const { return edges_; }
  const std::vector<Block>& blocks() const { return blocks_; }
  const std::vector<ParkingSlot>& slots() const { return slots_; }
  // Street edges leaving each node.
  const std::vector<std::vector<int>>& adjacency() const { return adjacency_; }
  // Static occluders (house, garage, fence, tree trunk and canopy, parked car boxes).
  const geometry::OccluderIndex& occluders() const { return occluders_; }
  // Entity owning occluder box i.
  int occluderOwner(int i) const { return occluder_owner_[static_cast<std::size_t>(i)]; }
  // Occluder boxes of entity e (empty for non-occluding classes).
  const std::vector<int>& occludersOf(int e) const { return entity_occluders_[static_cast<std::size_t>(e)]; }
  // Index over every entity's footprint (all classes), for neighbourhood queries.
  const geometry::OccluderIndex& footprints() const { return footprints_; }
  // Entity index by id, or -1.
  int find(const std::string& id) const;
  // The block containing p, or -1.
  int blockAt(const geometry::Vec2& p) const;
  // Neighborhood bounds (street centrelines of the outer ring).
  geometry::Aabb2 bounds() const { return bounds_; }
  // 64-bit FNV-1a fingerprint of the generated content, written into sim_config so that a
  // consumer that regenerates the world can check it got the same one.
  std::uint64_t fingerprint() const { return fingerprint_; }

  friend World generateWorld(const WorldParams& params);

 private:
  void finish();

  WorldParams params_;
  std::vector<Entity> entities_;
  std::vector<StreetNode> nodes_;
  std::vector<StreetEdge> edges_;
  std::vector<Block> blocks_;
  std::vector<ParkingSlot> slots_;
  std::vector<std::vector<int>> adjacency_;
  geometry::OccluderIndex occluders_{20.0};
  geometry::OccluderIndex footprints_{20.0};
  std::vector<int> occluder_owner_;
  std::vector<std::vector<int>> entity_occluders_;
  std::unordered_map<std::string, int> by_id_;
  geometry::Aabb2 bounds_;
  std::uint64_t fingerprint_ = 0;
};

// Generates the neighborhood for `params` (validated first).
World generateWorld(const WorldParams& params);

// Occluder boxes that stand for an entity in line-of-sight tests: a tree is a thin trunk under
// a canopy box, every other solid object its own box; streets and driveways occlude nothing.
std::vector<geometry::OrientedBox> occluderBoxes(const Entity& e);

}  // namespace hameritt::scenario
