#include "hameritt/scenario/entity.h"

#include <cmath>

namespace hameritt::scenario {

namespace {
struct ClassName {
  EntityClass cls;
  const char* name;
  int semantic;
};
constexpr ClassName kClassNames[] = {
    {EntityClass::kStreet, "street", 2},
    {EntityClass::kDriveway, "driveway", 3},
    {EntityClass::kHouse, "house", 4},
    {EntityClass::kGarage, "garage", 5},
    {EntityClass::kFence, "fence", 6},
    {EntityClass::kTree, "tree", 7},
    {EntityClass::kCar, "car", 8},
    {EntityClass::kPedestrian, "pedestrian", 9},
    {EntityClass::kBuilding, "building", 11},
    {EntityClass::kParkingGarage, "parking_garage", 12},
    {EntityClass::kParkingLot, "parking_lot", 13},
    {EntityClass::kAlley, "alley", 14},
    {EntityClass::kLampPost, "lamp_post", 15},
    {EntityClass::kTrafficLight, "traffic_light", 16},
    {EntityClass::kBusStop, "bus_stop", 17},
    {EntityClass::kBench, "bench", 18},
    {EntityClass::kStreetTree, "street_tree", 19},
    {EntityClass::kAircraft, "aircraft", 20},
};
}  // namespace

bool isSurfaceClass(EntityClass c) {
  return c == EntityClass::kStreet || c == EntityClass::kDriveway ||
         c == EntityClass::kParkingLot || c == EntityClass::kAlley;
}

const char* toString(EntityClass c) {
  for (const auto& n : kClassNames) {
    if (n.cls == c) return n.name;
  }
  return "unknown";
}

bool parseEntityClass(const std::string& s, EntityClass* out) {
  for (const auto& n : kClassNames) {
    if (s == n.name) {
      *out = n.cls;
      return true;
    }
  }
  return false;
}

int semanticId(EntityClass c) {
  for (const auto& n : kClassNames) {
    if (n.cls == c) return n.semantic;
  }
  return 0;
}

void Attributes::set(const std::string& key, AttributeValue v) {
  for (auto& kv : items) {
    if (kv.first == key) {
      kv.second = std::move(v);
      return;
    }
  }
  items.emplace_back(key, std::move(v));
}

std::string Attributes::str(const std::string& key) const {
  for (const auto& kv : items) {
    if (kv.first == key) {
      if (const auto* s = std::get_if<std::string>(&kv.second)) return *s;
      return "";
    }
  }
  return "";
}

std::int64_t Attributes::integer(const std::string& key, std::int64_t fallback) const {
  for (const auto& kv : items) {
    if (kv.first == key) {
      if (const auto* i = std::get_if<std::int64_t>(&kv.second)) return *i;
      return fallback;
    }
  }
  return fallback;
}

bool Attributes::has(const std::string& key) const {
  for (const auto& kv : items) {
    if (kv.first == key) return true;
  }
  return false;
}

geometry::OrientedBox boxFromPose(const geometry::Vec3& bottom_center, double yaw,
                                  const geometry::Vec3& size) {
  geometry::OrientedBox b;
  b.center = {bottom_center.x(), bottom_center.y(), bottom_center.z() + 0.5 * size.z()};
  b.size = size;
  b.yaw = yaw;
  return b;
}

double roundMilli(double v) {
  // std::round inline where it is exact: below 2^52, x - trunc(x) has no rounding error, so
  // comparing it with +-0.5 rounds half away from zero as std::round does. (A zero's sign may
  // differ from std::round's; zeros are returned as +0 below.)
  const double x = v * 1000.0;
  double n;
  if (std::abs(x) < 4503599627370496.0) {
    // The +-1 in integer arithmetic: compiled without branches (the fraction's side of 0.5 is
    // as good as random, so branches on it were mispredicted about half the time).
    long long k = static_cast<long long>(x);
    const double rest = x - static_cast<double>(k);
    k += static_cast<long long>(rest >= 0.5) - static_cast<long long>(rest <= -0.5);
    n = static_cast<double>(k);
  } else {
    n = std::round(x);
  }
  const double r = n / 1000.0;
  return r == 0.0 ? 0.0 : r;  // no negative zero in the output
}

}  // namespace hameritt::scenario
