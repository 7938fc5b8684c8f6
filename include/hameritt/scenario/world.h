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

// Which kind of place generateWorld() builds.
enum class WorldType {
  kSuburb,  // 1-2 storey houses on large lots (the default)
  kCity,    // a dense downtown grid: mid-rise blocks, towers, alleys, street furniture
};

// Parameters of the city world type (the "city" object of config/world.json); used only when
// WorldParams::type is kCity. Lengths in metres. Every field has an allowed range, listed in
// cityFieldTable(); validate() names the key and that range.
struct CityParams {
  double arterial_width = 24.0;     // right-of-way of the 4-lane arterials, [20, 30]
  double arterial_every = 3.0;      // every n-th street of each direction is an arterial, [2, 6]
  double local_width = 14.0;        // right-of-way of local streets, [12, 18]
  double alley_width = 5.0;         // mid-block service alleys, [4, 6]
  double sidewalk_width = 3.0;      // [1.8, 6]
  double block_length_min = 120.0;  // spacing of north-south streets, within [60, 200]
  double block_length_max = 170.0;
  double block_depth_min = 85.0;  // spacing of east-west streets, within [60, 120]
  double block_depth_max = 110.0;
  double intersection_jitter = 2.0;  // [0, 5]
  double lot_frontage_min = 12.0;    // within [10, 30]
  double lot_frontage_max = 26.0;
  double storey_height = 3.5;      // [2.8, 4.5]
  double median_storeys = 7.0;     // median of the lognormal storey count, [6, 8]
  double storeys_sigma = 0.35;     // log-space standard deviation, [0.1, 0.8]
  double tower_share = 0.07;       // share of buildings that are towers, [0.05, 0.10]
  double tower_height_min = 60.0;  // within [60, 150]
  double tower_height_max = 150.0;
  double downtown_radius = 300.0;  // towers stand within this distance of the centre, [100, 1000]
  double parking_garage_share = 0.04;        // share of lots holding a parking garage, [0, 0.2]
  double surface_lot_share = 0.04;           // share of lots holding a surface car park, [0, 0.2]
  double street_parking_probability = 0.45;  // per kerb slot on local streets, [0, 1]
  double lot_parking_probability = 0.6;      // per surface-lot stall, [0, 1]
  double lamp_spacing = 30.0;                // lamp posts along each kerb, [15, 60]
  double tree_spacing = 15.0;                // street trees along local-street kerbs, [6, 40]
  double bench_probability = 0.3;            // per block side, [0, 1]
  double bus_stop_probability = 0.6;         // per arterial block side, [0, 1]
  // Signals and ambient traffic (generated per scenario into sim_config.json).
  double signal_green = 15.0;          // through green of each axis (s), [5, 60]
  double signal_yellow = 4.0;          // [3, 6]
  double signal_left = 7.0;            // protected left arrow before each green (s), [0, 20]
  double signal_all_red = 2.0;         // clearance after each yellow (s), [1, 5]
  double vehicles_per_km2 = 170.0;     // ambient cars driving the arterials, [0, 400]
  double pedestrians_per_km2 = 400.0;  // [0, 2000]
  double crossing_share = 0.3;         // share of pedestrians who cross a street, [0, 1]
  double jaywalk_probability = 0.15;   // a crossing is mid-block, off the signals, [0, 1]
  double bus_queue_share = 0.08;       // share of pedestrians queueing at bus stops, [0, 0.5]
  double traffic_episodes = 8.0;  // car runs per world that scenarios draw from, integer [1, 64]

  // Throws ConfigError "world.city.KEY: expected LO to HI, got V" for the first bad field.
  void validate() const;
};

// One row of the city parameter table: JSON key, member and allowed range.
struct CityField {
  const char* key;
  double CityParams::*member;
  double min;
  double max;
};
// Every CityParams field with its allowed range, in JSON order.
const std::vector<CityField>& cityFieldTable();

// "suburb" or "city".
const char* toString(WorldType t);
// Parses "suburb" or "city"; returns false for anything else.
bool parseWorldType(const std::string& s, WorldType* out);

// World generation parameters (config/world.json). Lengths in metres.
struct WorldParams {
  WorldType type = WorldType::kSuburb;  // written only when not the default
  CityParams city;                      // used (and written) only for kCity
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

  // Sidewalk width of this world type (WorldParams::sidewalk_width or city.sidewalk_width).
  double sidewalkWidth() const;
  // Widest street right-of-way of the network.
  double maxStreetWidth() const;

  friend World generateWorld(const WorldParams& params);
  friend void buildCityWorld(const WorldParams& params, World* world);

 private:
  void finish();

  WorldParams params_;
  std::vector<Entity> entities_;
  std::vector<StreetNode> nodes_;
  std::vector<StreetEdge> edges_;
  std::vector<Block> blocks_;
  std::vector<geometry::Aabb2> block_bounds_;  // each block outline's bounds (finish())
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

// Generates the neighborhood for `params` (validated first): the suburb, or the city of
// src/scenario/city_world.cpp when params.type is kCity.
World generateWorld(const WorldParams& params);

// Fills `world` (fresh) with the city of params.city, on the tile extent_x by extent_y; called
// by generateWorld().
void buildCityWorld(const WorldParams& params, World* world);

// Occluder boxes that stand for an entity in line-of-sight tests: a tree is a thin trunk under
// a canopy box, every other solid object its own box; streets and driveways occlude nothing.
std::vector<geometry::OrientedBox> occluderBoxes(const Entity& e);

}  // namespace hameritt::scenario
