#pragma once
// Entities of the neighborhood and of a scenario: every object has an id, a class, attributes,
// a pose with yaw and an oriented 3D bounding box.

#include <cstdint>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "hameritt/geometry/oriented_box.h"

namespace hameritt::scenario {

enum class EntityClass {
  kStreet,
  kDriveway,
  kHouse,
  kGarage,
  kFence,
  kTree,
  kCar,
  kPedestrian,
  // City classes (the city world type).
  kBuilding,       // a mid-rise building or tower on a city lot
  kParkingGarage,  // a multi-storey car park
  kParkingLot,     // a surface car park (a surface, like a driveway)
  kAlley,          // a mid-block service alley (a surface, like a street)
  kLampPost,
  kTrafficLight,  // a signal mast at an arterial intersection
  kBusStop,       // a bus shelter on an arterial sidewalk
  kBench,
  kStreetTree,  // a sidewalk tree in a pit at the kerb
  kAircraft,    // another aircraft of an avoid scenario (SimConfig::aircraft)
};

// True for the classes that are driving or parking surfaces (street, driveway, parking_lot,
// alley): they occlude nothing and relations treat them as ground to stand on.
bool isSurfaceClass(EntityClass c);

// Lower-case name used in JSON ("street", "driveway", "house", ...).
const char* toString(EntityClass c);
// Parses a class name; returns false for an unknown name.
bool parseEntityClass(const std::string& s, EntityClass* out);
// Semantic segmentation id of a class (0 is reserved for sky/background, 1 for ground).
int semanticId(EntityClass c);

using AttributeValue = std::variant<std::string, std::int64_t>;

// An ordered attribute list (insertion order is kept so that output is stable).
struct Attributes {
  std::vector<std::pair<std::string, AttributeValue>> items;

  void set(const std::string& key, AttributeValue v);
  // The string value of `key`, or "" when absent or not a string.
  std::string str(const std::string& key) const;
  // The integer value of `key`, or `fallback` when absent or not an integer.
  std::int64_t integer(const std::string& key, std::int64_t fallback = 0) const;
  bool has(const std::string& key) const;
  bool operator==(const Attributes& o) const { return items == o.items; }
};

// A physical object. The pose is the centre of the box's bottom face plus yaw; `box` is the
// full oriented box (its centre is half a height above the pose).
struct Entity {
  std::string id;
  EntityClass cls = EntityClass::kHouse;
  Attributes attributes;
  geometry::OrientedBox box;
  // Index of the block (group) the object stands in, or -1 (streets, sidewalks).
  int block = -1;

  geometry::Vec3 position() const {
    return {box.center.x(), box.center.y(), box.minZ()};
  }
  double yaw() const { return box.yaw; }
};

// Builds an entity box from a bottom-centre position, yaw and size (length, width, height).
geometry::OrientedBox boxFromPose(const geometry::Vec3& bottom_center, double yaw,
                                  const geometry::Vec3& size);

// Rounds to a multiple of 1/1000 (millimetres; milliradians) so that written values equal
// the values that relations were computed from.
double roundMilli(double v);

}  // namespace hameritt::scenario
