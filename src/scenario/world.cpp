#include "hameritt/scenario/world.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "hameritt/scenario/catalog.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/rng.h"
#include "world_entities.h"

namespace hameritt::scenario {

using geometry::OrientedBox;
using geometry::Polygon;
using geometry::Vec2;
using geometry::Vec3;

namespace {

void requirePositive(const char* field, double v) {
  if (!(std::isfinite(v) && v > 0.0)) {
    std::ostringstream os;
    os << "world." << field << ": expected a positive number, got " << v;
    throw ConfigError(os.str());
  }
}

void requireProbability(const char* field, double v) {
  if (!(std::isfinite(v) && v >= 0.0 && v <= 1.0)) {
    std::ostringstream os;
    os << "world." << field << ": expected a probability in [0, 1], got " << v;
    throw ConfigError(os.str());
  }
}

void requireRange(const char* lo_field, double lo, const char* hi_field, double hi) {
  if (lo > hi) {
    std::ostringstream os;
    os << "world." << lo_field << " (" << lo << ") must not exceed world." << hi_field << " ("
       << hi << ")";
    throw ConfigError(os.str());
  }
}

// Intersection of the lines p + t*d and q + s*e (not parallel).
Vec2 lineIntersection(const Vec2& p, const Vec2& d, const Vec2& q, const Vec2& e) {
  const double den = geometry::cross2(d, e);
  if (std::abs(den) < 1e-12) return p;
  const double t = geometry::cross2(q - p, e) / den;
  return p + t * d;
}

// Insets a convex counter-clockwise polygon by `by` metres on every edge.
Polygon insetConvex(const Polygon& poly, double by) {
  const auto& v = poly.vertices();
  const std::size_t n = v.size();
  std::vector<Vec2> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& a0 = v[(i + n - 1) % n];
    const Vec2& a1 = v[i];
    const Vec2& b1 = v[(i + 1) % n];
    const Vec2 d0 = (a1 - a0).normalized();
    const Vec2 d1 = (b1 - a1).normalized();
    const Vec2 n0(-d0.y(), d0.x());  // inward normal of a counter-clockwise ring
    const Vec2 n1(-d1.y(), d1.x());
    out.push_back(lineIntersection(a0 + by * n0, d0, a1 + by * n1, d1));
  }
  return Polygon(out);
}

class WorldBuilder {
 public:
  WorldBuilder(const WorldParams& p, World* w) : p_(p), rng_(deriveSeed(p.seed, 0x574F524C44ULL)), w_(w) {}

  void build(std::vector<Entity>* entities, std::vector<StreetNode>* nodes,
             std::vector<StreetEdge>* edges, std::vector<Block>* blocks,
             std::vector<ParkingSlot>* slots, geometry::Aabb2* bounds) {
    entities_ = entities;
    slots_ = slots;
    buildGrid(nodes, edges, bounds);
    buildBlocks(*nodes, blocks);
    for (auto& b : *blocks) buildLots(b);
    buildKerbSlots(*nodes, *edges, *blocks);
    parkWorldCars();
  }

 private:
  int addEntity(EntityClass cls, const std::string& prefix, const Vec3& bottom, double yaw,
                const Vec3& size, Attributes attrs, int block) {
    return world_entities::appendEntity(entities_, &counters_, cls, prefix, bottom, yaw, size,
                                        std::move(attrs), block);
  }

  void buildGrid(std::vector<StreetNode>* nodes, std::vector<StreetEdge>* edges,
                 geometry::Aabb2* bounds) {
    // Street positions along each axis: spacing drawn from the block ranges until the extent
    // is covered, then scaled to fit exactly.
    auto positions = [this](double extent, double lo, double hi) {
      std::vector<double> gaps;
      double total = 0.0;
      while (total < extent - 0.5 * lo) {
        const double g = rng_.uniform(lo, hi);
        gaps.push_back(g);
        total += g;
      }
      if (gaps.empty()) gaps.push_back(extent);
      const double scale = extent / std::max(total, 1e-9);
      std::vector<double> out{-0.5 * extent};
      for (double g : gaps) out.push_back(out.back() + g * scale);
      out.back() = 0.5 * extent;
      return out;
    };
    xs_ = positions(p_.extent_x, p_.block_length_min, p_.block_length_max);
    ys_ = positions(p_.extent_y, p_.block_depth_min, p_.block_depth_max);
    nx_ = static_cast<int>(xs_.size());
    ny_ = static_cast<int>(ys_.size());
    for (int j = 0; j < ny_; ++j) {
      for (int i = 0; i < nx_; ++i) {
        Vec2 pos(xs_[i], ys_[j]);
        const bool border = i == 0 || j == 0 || i == nx_ - 1 || j == ny_ - 1;
        if (!border) {
          pos.x() += rng_.uniform(-p_.intersection_jitter, p_.intersection_jitter);
          pos.y() += rng_.uniform(-p_.intersection_jitter, p_.intersection_jitter);
        }
        nodes->push_back({Vec2(roundMilli(pos.x()), roundMilli(pos.y()))});
      }
    }
    bounds->min = Vec2(xs_.front(), ys_.front());
    bounds->max = Vec2(xs_.back(), ys_.back());
    // North-south streets are named from kStreetNamesNS, east-west from kStreetNamesEW.
    auto addEdge = [&](int a, int b, const std::string& name, const std::string& from,
                       const std::string& to) {
      StreetEdge e;
      e.a = a;
      e.b = b;
      e.width = p_.street_width;
      e.name = name;
      const Vec2 pa = (*nodes)[a].position, pb = (*nodes)[b].position;
      const Vec2 mid = 0.5 * (pa + pb);
      const Vec2 d = pb - pa;
      Attributes attrs;
      attrs.set("name", name);
      attrs.set("between", from + " and " + to);
      // Street surface: a slab whose top is the ground plane z = 0.
      e.entity = addEntity(EntityClass::kStreet, "street", Vec3(mid.x(), mid.y(), -0.1),
                           std::atan2(d.y(), d.x()), Vec3(d.norm() + p_.street_width, p_.street_width, 0.1),
                           attrs, -1);
      edges->push_back(e);
    };
    // Each segment is also named by the cross streets at its ends.
    for (int j = 0; j < ny_; ++j) {
      const std::string name = catalog::streetName(false, j);
      for (int i = 0; i + 1 < nx_; ++i) {
        addEdge(j * nx_ + i, j * nx_ + i + 1, name, catalog::streetName(true, i),
                catalog::streetName(true, i + 1));
      }
    }
    for (int i = 0; i < nx_; ++i) {
      const std::string name = catalog::streetName(true, i);
      for (int j = 0; j + 1 < ny_; ++j) {
        addEdge(j * nx_ + i, (j + 1) * nx_ + i, name, catalog::streetName(false, j),
                catalog::streetName(false, j + 1));
      }
    }
  }

  void buildBlocks(const std::vector<StreetNode>& nodes, std::vector<Block>* blocks) {
    for (int j = 0; j + 1 < ny_; ++j) {
      for (int i = 0; i + 1 < nx_; ++i) {
        Block b;
        b.index = static_cast<int>(blocks->size());
        char name[32];
        std::snprintf(name, sizeof(name), "block_%02d", b.index + 1);
        b.name = name;
        b.outline = Polygon({nodes[j * nx_ + i].position, nodes[j * nx_ + i + 1].position,
                             nodes[(j + 1) * nx_ + i + 1].position,
                             nodes[(j + 1) * nx_ + i].position});
        b.interior = insetConvex(b.outline, 0.5 * p_.street_width + p_.sidewalk_width);
        const Polygon walk = insetConvex(b.outline, 0.5 * p_.street_width + 0.5 * p_.sidewalk_width);
        b.sidewalk = walk.vertices();
        for (auto& v : b.sidewalk) v = Vec2(roundMilli(v.x()), roundMilli(v.y()));
        b.sidewalk.push_back(b.sidewalk.front());
        blocks->push_back(std::move(b));
      }
    }
  }

  // Lots along each side of the block interior. Long sides span the full side; short sides
  // fill what the long sides' lots leave. A lot is kept only if it overlaps no earlier lot.
  void buildLots(const Block& block) {
    const auto& v = block.interior.vertices();
    std::vector<Polygon> placed;
    double side_len[4];
    for (int s = 0; s < 4; ++s) side_len[s] = (v[(s + 1) % 4] - v[s]).norm();
    const bool ew_long = side_len[0] + side_len[2] >= side_len[1] + side_len[3];
    const double short_len = ew_long ? std::min(side_len[1], side_len[3])
                                     : std::min(side_len[0], side_len[2]);
    const double depth = std::min(p_.lot_depth, 0.5 * short_len - 1.0);
    if (depth < 20.0) return;
    const int bi = block.index % (nx_ - 1), bj = block.index / (nx_ - 1);
    for (int pass = 0; pass < 2; ++pass) {
      for (int s = 0; s < 4; ++s) {
        const bool is_long = ((s % 2) == 0) == ew_long;
        if ((pass == 0) != is_long) continue;
        // Sides 0..3 face the south, east, north and west streets of the block.
        const int street_index[4] = {bj, bi + 1, bj + 1, bi};
        street_name_ = catalog::streetName(s % 2 == 1, street_index[s]);
        const Vec2 a = v[s], b = v[(s + 1) % 4];
        const double len = (b - a).norm();
        const Vec2 u = (b - a) / len;
        const Vec2 n(-u.y(), u.x());  // into the block
        double start = is_long ? 1.0 : depth + 2.0;
        const double end = is_long ? len - 1.0 : len - depth - 2.0;
        while (end - start >= p_.lot_frontage_min) {
          double w = rng_.uniform(p_.lot_frontage_min, p_.lot_frontage_max);
          if (end - start - w < p_.lot_frontage_min) w = end - start;
          if (w > p_.lot_frontage_max + p_.lot_frontage_min) w = p_.lot_frontage_max;
          const Vec2 o = a + start * u;
          Polygon lot({o, o + w * u, o + w * u + depth * n, o + depth * n});
          bool clash = false;
          const Polygon shrunk({o + 0.2 * u + 0.2 * n, o + (w - 0.2) * u + 0.2 * n,
                                o + (w - 0.2) * u + (depth - 0.2) * n, o + 0.2 * u + (depth - 0.2) * n});
          for (const auto& q : placed) clash = clash || q.intersects(shrunk);
          for (const auto& c : shrunk.vertices()) clash = clash || !block.interior.contains(c);
          if (!clash) {
            placed.push_back(lot);
            buildLot(block, o, u, n, w, depth);
          }
          start += w;
        }
      }
    }
  }

  void buildLot(const Block& block, const Vec2& o, const Vec2& u, const Vec2& n, double w,
                double depth) {
    auto at = [&](double du, double dv) { return o + du * u + dv * n; };
    const double yaw_in = std::atan2(n.y(), n.x());  // facing into the lot
    const int bi = block.index;
    const int number = 2 * (++house_numbers_) + (rng_.bernoulli(0.5) ? 1 : 0);

    const bool garage = rng_.bernoulli(p_.garage_probability);
    const int doors = garage && rng_.bernoulli(p_.two_door_garage_probability) ? 2 : 1;
    const double gw = doors == 2 ? rng_.uniform(6.2, 7.0) : rng_.uniform(3.6, 4.2);
    const double gd = rng_.uniform(6.2, 7.2);
    const double setback = rng_.uniform(7.0, 10.0);
    const double right_reserve = garage ? gw + 2.5 : 5.0;  // garage or a bare driveway
    const double house_w = std::clamp(w - right_reserve - 3.0, 8.0, 14.0);
    const double house_d = rng_.uniform(8.0, std::min(12.0, depth - setback - 4.0));
    const int storeys = rng_.bernoulli(0.55) ? 2 : 1;
    const double house_h = storeys == 2 ? rng_.uniform(7.0, 9.0) : rng_.uniform(4.5, 6.0);

    Attributes ha;
    ha.set("color", catalog::pick(rng_, catalog::houseColors()));
    ha.set("storeys", static_cast<std::int64_t>(storeys));
    ha.set("address", std::to_string(number) + " " + street_name_);
    const Vec2 hc = at(1.5 + 0.5 * house_w, setback + 0.5 * house_d);
    addEntity(EntityClass::kHouse, "house", Vec3(hc.x(), hc.y(), 0.0),
              yaw_in, Vec3(house_d, house_w, house_h), ha, bi);

    // Driveway from the kerb line to the garage door (or to beside the house).
    const double drive_u = garage ? w - 1.2 - 0.5 * gw : w - 2.8;
    const double drive_w = garage ? gw + 0.4 : 3.2;
    const double garage_v0 = setback + rng_.uniform(0.5, 3.0);
    const double drive_len = garage ? garage_v0 : setback + 0.5 * house_d;
    {
      Attributes da;
      da.set("material", rng_.bernoulli(0.6) ? std::string("concrete") : std::string("asphalt"));
      const Vec2 dc = at(drive_u, 0.5 * drive_len);
      addEntity(EntityClass::kDriveway, "driveway", Vec3(dc.x(), dc.y(), 0.0), yaw_in,
                Vec3(drive_len, drive_w, p_.driveway_height), da, bi);
    }
    if (garage) {
      Attributes ga;
      ga.set("color", catalog::pick(rng_, catalog::garageColors()));
      ga.set("doors", static_cast<std::int64_t>(doors));
      const Vec2 gc = at(drive_u, garage_v0 + 0.5 * gd);
      addEntity(EntityClass::kGarage, "garage", Vec3(gc.x(), gc.y(), 0.0), yaw_in,
                Vec3(gd, gw, rng_.uniform(2.8, 3.5)), ga, bi);
    }
    // Driveway slots: one per garage door, a car length in front of the door.
    const double car_len = 5.0;
    const double slot_v = garage ? garage_v0 - 0.5 - 0.5 * car_len : drive_len - 0.5 * car_len - 0.3;
    for (int d = 0; d < doors; ++d) {
      const double du = doors == 2 ? drive_u + (d == 0 ? -1.0 : 1.0) * 0.25 * gw : drive_u;
      ParkingSlot s;
      const Vec2 c = at(du, slot_v);
      s.position = Vec2(roundMilli(c.x()), roundMilli(c.y()));
      // Nose in (towards the garage) or nose out (towards the street).
      s.yaw = roundMilli(geometry::wrapPi(rng_.bernoulli(0.5) ? yaw_in : yaw_in + geometry::kPi));
      s.ground_z = roundMilli(p_.driveway_height);
      s.driveway = true;
      s.block = bi;
      slots_->push_back(s);
    }
    // Fence along the back line and along the left side behind the house.
    if (rng_.bernoulli(p_.fence_probability)) {
      Attributes fa;
      fa.set("color", catalog::pick(rng_, catalog::fenceColors()));
      fa.set("material", catalog::pick(rng_, catalog::fenceMaterials()));
      const double fh = rng_.uniform(1.2, 1.9);
      const Vec2 back = at(0.5 * w, depth - 0.1);
      addEntity(EntityClass::kFence, "fence", Vec3(back.x(), back.y(), 0.0),
                yaw_in + 0.5 * geometry::kPi, Vec3(w - 0.4, 0.12, fh), fa, bi);
      const double side_v0 = setback + house_d + 1.0;
      if (depth - side_v0 > 3.0) {
        const Vec2 side = at(0.1, 0.5 * (side_v0 + depth - 0.3));
        addEntity(EntityClass::kFence, "fence", Vec3(side.x(), side.y(), 0.0), yaw_in,
                  Vec3(depth - 0.3 - side_v0, 0.12, fh), fa, bi);
      }
    }
    // Trees on the front lawn and in the back yard, clear of the buildings and driveway.
    const int trees = static_cast<int>(rng_.uniform(0.0, p_.trees_per_lot_max + 0.999));
    for (int t = 0; t < trees; ++t) {
      const double diam = rng_.uniform(3.0, 7.5);
      const bool front = rng_.bernoulli(0.5);
      double du = rng_.uniform(0.5 * diam, std::max(0.5 * diam, w - 0.5 * diam));
      double dv = front ? rng_.uniform(1.0, std::max(1.0, setback - 1.0))
                        : rng_.uniform(setback + house_d + 0.5 * diam + 0.5,
                                       std::max(setback + house_d + 0.5 * diam + 0.5, depth - 0.5 * diam));
      const Vec2 c = at(du, dv);
      const double clearance = 0.5 * diam * 0.6;
      bool ok = true;
      for (std::size_t k = lot_first_entity_; k < entities_->size() && ok; ++k) {
        const auto& e = (*entities_)[k];
        if (e.cls == EntityClass::kStreet) continue;
        if (e.box.footprint().distance(c) < clearance) ok = false;
      }
      if (!ok) continue;
      Attributes ta;
      ta.set("species", catalog::pick(rng_, catalog::treeSpecies()));
      ta.set("foliage", rng_.bernoulli(0.7) ? std::string("leafy") : std::string("sparse"));
      // One draw per statement, in the order g++ evaluated the arguments of the call these were
      // once (right to left; C++ leaves it to the compiler): the golden files pin it.
      const double height = rng_.uniform(5.0, 13.0);
      const double yaw = rng_.uniform(-3.14, 3.14);
      addEntity(EntityClass::kTree, "tree", Vec3(c.x(), c.y(), 0.0), yaw, Vec3(diam, diam, height), ta, bi);
    }
    lot_first_entity_ = entities_->size();
  }

  // Kerb parking slots every 7 m on both sides of each street edge, keeping clear of the
  // intersections and of driveway mouths.
  void buildKerbSlots(const std::vector<StreetNode>& nodes, const std::vector<StreetEdge>& edges,
                      const std::vector<Block>& blocks) {
    geometry::OccluderIndex driveways(20.0);
    for (const auto& e : *entities_) {
      if (e.cls == EntityClass::kDriveway) driveways.add(e.box);
    }
    driveways.build();
    world_entities::addKerbSlots(
        nodes, edges, blocks, driveways, 4.5, 7.0,
        [](const StreetEdge& e) { return 0.5 * e.width + 8.0; }, slots_);
  }

  void parkWorldCars() {
    world_entities::parkCars(rng_, p_.driveway_car_probability, p_.street_parking_probability,
                             slots_, entities_, &counters_);
  }

  const WorldParams& p_;
  Rng rng_;
  World* w_;
  std::vector<Entity>* entities_ = nullptr;
  std::vector<ParkingSlot>* slots_ = nullptr;
  std::vector<double> xs_, ys_;
  int nx_ = 0, ny_ = 0;
  world_entities::EntityCounters counters_;
  int house_numbers_ = 0;
  std::size_t lot_first_entity_ = 0;
  std::string street_name_;
};

std::uint64_t fnv1a(std::uint64_t h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 0x100000001B3ULL;
  }
  return h;
}

}  // namespace

void WorldParams::validate() const {
  if (type == WorldType::kCity) {
    // The city is a tile of 0.5 to 2 km a side; the suburb fields below stay checked so that
    // a file can switch type without other edits.
    for (const auto& [key, v] : {std::pair<const char*, double>{"extent_x", extent_x},
                                 std::pair<const char*, double>{"extent_y", extent_y}}) {
      if (!(v >= 500.0 && v <= 2000.0)) {
        std::ostringstream os;
        os << "world." << key << ": expected 500 to 2000 (m) for the city, got " << v;
        throw ConfigError(os.str());
      }
    }
    city.validate();
  }
  requirePositive("extent_x", extent_x);
  requirePositive("extent_y", extent_y);
  requirePositive("block_length_min", block_length_min);
  requirePositive("block_depth_min", block_depth_min);
  requireRange("block_length_min", block_length_min, "block_length_max", block_length_max);
  requireRange("block_depth_min", block_depth_min, "block_depth_max", block_depth_max);
  if (block_length_min < 80.0 || block_depth_min < 80.0) {
    throw ConfigError("world.block_length_min/block_depth_min: expected at least 80 m so that "
                      "lots fit, got " + std::to_string(std::min(block_length_min, block_depth_min)));
  }
  if (extent_x > 5000.0 || extent_y > 5000.0) {
    throw ConfigError("world.extent_x/extent_y: expected at most 5000 m");
  }
  if (!(intersection_jitter >= 0.0 && intersection_jitter <= 0.1 * block_depth_min)) {
    throw ConfigError("world.intersection_jitter: expected 0 to a tenth of block_depth_min, got " +
                      std::to_string(intersection_jitter));
  }
  if (!(street_width >= 9.5 && street_width <= 30.0)) {
    throw ConfigError("world.street_width: expected 9.5 to 30 m (two lanes and kerb parking), got " +
                      std::to_string(street_width));
  }
  requirePositive("sidewalk_width", sidewalk_width);
  requirePositive("lot_frontage_min", lot_frontage_min);
  requireRange("lot_frontage_min", lot_frontage_min, "lot_frontage_max", lot_frontage_max);
  if (lot_frontage_min < 16.0) {
    throw ConfigError("world.lot_frontage_min: expected at least 16 m (house, garage and "
                      "driveway must fit), got " + std::to_string(lot_frontage_min));
  }
  if (lot_depth < 24.0) {
    throw ConfigError("world.lot_depth: expected at least 24 m, got " + std::to_string(lot_depth));
  }
  requireProbability("garage_probability", garage_probability);
  requireProbability("two_door_garage_probability", two_door_garage_probability);
  requireProbability("fence_probability", fence_probability);
  requireProbability("driveway_car_probability", driveway_car_probability);
  requireProbability("street_parking_probability", street_parking_probability);
  if (!(trees_per_lot_max >= 0.0 && trees_per_lot_max <= 10.0)) {
    throw ConfigError("world.trees_per_lot_max: expected 0 to 10, got " +
                      std::to_string(trees_per_lot_max));
  }
  requirePositive("driveway_height", driveway_height);
}

std::vector<OrientedBox> occluderBoxes(const Entity& e) {
  if (isSurfaceClass(e.cls)) return {};
  switch (e.cls) {
    case EntityClass::kTree:
    case EntityClass::kStreetTree: {
      // Trunk under the lower third, canopy above it.
      const double h = e.box.size.z();
      const double base = e.box.minZ();
      OrientedBox trunk = boxFromPose(Vec3(e.box.center.x(), e.box.center.y(), base), e.box.yaw,
                                      Vec3(0.4, 0.4, h / 3.0));
      OrientedBox canopy = boxFromPose(Vec3(e.box.center.x(), e.box.center.y(), base + h / 3.0),
                                       e.box.yaw, Vec3(e.box.size.x(), e.box.size.y(), h * 2.0 / 3.0));
      return {trunk, canopy};
    }
    default:
      return {e.box};
  }
}

int World::find(const std::string& id) const {
  const auto it = by_id_.find(id);
  return it == by_id_.end() ? -1 : it->second;
}

int World::blockAt(const Vec2& p) const {
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    if (block_bounds_[i].contains(p) && blocks_[i].outline.contains(p)) return blocks_[i].index;
  }
  return -1;
}

void World::finish() {
  block_bounds_.clear();
  for (const auto& b : blocks_) block_bounds_.push_back(b.outline.bounds());
  entity_occluders_.assign(entities_.size(), {});
  for (int i = 0; i < static_cast<int>(entities_.size()); ++i) {
    const auto& e = entities_[i];
    by_id_[e.id] = i;
    footprints_.add(e.box);
    for (const auto& b : occluderBoxes(e)) {
      entity_occluders_[i].push_back(occluders_.add(b));
      occluder_owner_.push_back(i);
    }
  }
  occluders_.build();
  footprints_.build();
  // Fingerprint over ids, classes and boxes (as written, millimetre-rounded values).
  std::uint64_t h = 0xCBF29CE484222325ULL;
  for (const auto& e : entities_) {
    h = fnv1a(h, e.id.data(), e.id.size());
    const std::int64_t vals[] = {static_cast<std::int64_t>(e.cls),
                                 std::llround(e.box.center.x() * 1000),
                                 std::llround(e.box.center.y() * 1000),
                                 std::llround(e.box.minZ() * 1000),
                                 std::llround(e.box.size.x() * 1000),
                                 std::llround(e.box.size.y() * 1000),
                                 std::llround(e.box.size.z() * 1000),
                                 std::llround(e.box.yaw * 1000)};
    h = fnv1a(h, vals, sizeof(vals));
  }
  fingerprint_ = h;
}

double World::sidewalkWidth() const {
  return params_.type == WorldType::kCity ? params_.city.sidewalk_width : params_.sidewalk_width;
}

double World::maxStreetWidth() const {
  double w = 0.0;
  for (const auto& e : edges_) w = std::max(w, e.width);
  return w;
}

World generateWorld(const WorldParams& params) {
  params.validate();
  World w;
  w.params_ = params;
  if (params.type == WorldType::kCity) {
    buildCityWorld(params, &w);
  } else {
    WorldBuilder builder(w.params_, &w);
    builder.build(&w.entities_, &w.nodes_, &w.edges_, &w.blocks_, &w.slots_, &w.bounds_);
  }
  w.adjacency_.assign(w.nodes_.size(), {});
  for (int i = 0; i < static_cast<int>(w.edges_.size()); ++i) {
    w.adjacency_[w.edges_[i].a].push_back(i);
    w.adjacency_[w.edges_[i].b].push_back(i);
  }
  w.finish();
  return w;
}

}  // namespace hameritt::scenario
