// The city world type: a jittered street grid of 4-lane arterials and local streets, blocks
// split by a service alley into two rows of lots, mid-rise buildings with a lognormal storey
// count and towers in a downtown core, parking garages and surface car parks, kerb parking and
// street furniture (lamp posts, street trees, benches, bus stops, traffic lights).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

#include "hameritt/scenario/catalog.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/scenario/world.h"
#include "world_entities.h"

namespace hameritt::scenario {

using geometry::Polygon;
using geometry::Vec2;
using geometry::Vec3;

const std::vector<CityField>& cityFieldTable() {
  static const std::vector<CityField> k = {
      {"arterial_width", &CityParams::arterial_width, 20.0, 30.0},
      {"arterial_every", &CityParams::arterial_every, 2.0, 6.0},
      {"local_width", &CityParams::local_width, 12.0, 18.0},
      {"alley_width", &CityParams::alley_width, 4.0, 6.0},
      {"sidewalk_width", &CityParams::sidewalk_width, 1.8, 6.0},
      {"block_length_min", &CityParams::block_length_min, 60.0, 200.0},
      {"block_length_max", &CityParams::block_length_max, 60.0, 200.0},
      {"block_depth_min", &CityParams::block_depth_min, 60.0, 120.0},
      {"block_depth_max", &CityParams::block_depth_max, 60.0, 120.0},
      {"intersection_jitter", &CityParams::intersection_jitter, 0.0, 5.0},
      {"lot_frontage_min", &CityParams::lot_frontage_min, 10.0, 30.0},
      {"lot_frontage_max", &CityParams::lot_frontage_max, 10.0, 30.0},
      {"storey_height", &CityParams::storey_height, 2.8, 4.5},
      {"median_storeys", &CityParams::median_storeys, 6.0, 8.0},
      {"storeys_sigma", &CityParams::storeys_sigma, 0.1, 0.8},
      {"tower_share", &CityParams::tower_share, 0.05, 0.10},
      {"tower_height_min", &CityParams::tower_height_min, 60.0, 150.0},
      {"tower_height_max", &CityParams::tower_height_max, 60.0, 150.0},
      {"downtown_radius", &CityParams::downtown_radius, 100.0, 1000.0},
      {"parking_garage_share", &CityParams::parking_garage_share, 0.0, 0.2},
      {"surface_lot_share", &CityParams::surface_lot_share, 0.0, 0.2},
      {"street_parking_probability", &CityParams::street_parking_probability, 0.0, 1.0},
      {"lot_parking_probability", &CityParams::lot_parking_probability, 0.0, 1.0},
      {"lamp_spacing", &CityParams::lamp_spacing, 15.0, 60.0},
      {"tree_spacing", &CityParams::tree_spacing, 6.0, 40.0},
      {"bench_probability", &CityParams::bench_probability, 0.0, 1.0},
      {"bus_stop_probability", &CityParams::bus_stop_probability, 0.0, 1.0},
      {"signal_green", &CityParams::signal_green, 5.0, 60.0},
      {"signal_yellow", &CityParams::signal_yellow, 3.0, 6.0},
      {"signal_left", &CityParams::signal_left, 0.0, 20.0},
      {"signal_all_red", &CityParams::signal_all_red, 1.0, 5.0},
      {"vehicles_per_km2", &CityParams::vehicles_per_km2, 0.0, 400.0},
      {"pedestrians_per_km2", &CityParams::pedestrians_per_km2, 0.0, 2000.0},
      {"crossing_share", &CityParams::crossing_share, 0.0, 1.0},
      {"jaywalk_probability", &CityParams::jaywalk_probability, 0.0, 1.0},
      {"bus_queue_share", &CityParams::bus_queue_share, 0.0, 0.5},
      {"traffic_episodes", &CityParams::traffic_episodes, 1.0, 64.0},
  };
  return k;
}

void CityParams::validate() const {
  for (const auto& f : cityFieldTable()) {
    const double v = this->*(f.member);
    if (!(std::isfinite(v) && v >= f.min && v <= f.max)) {
      std::ostringstream os;
      os << "world.city." << f.key << ": expected " << f.min << " to " << f.max << ", got " << v;
      throw ConfigError(os.str());
    }
  }
  if (traffic_episodes != std::floor(traffic_episodes)) {
    std::ostringstream os;
    os << "world.city.traffic_episodes: expected an integer from 1 to 64, got " << traffic_episodes;
    throw ConfigError(os.str());
  }
  auto ordered = [](const char* lo_key, double lo, const char* hi_key, double hi) {
    if (lo > hi) {
      std::ostringstream os;
      os << "world.city." << lo_key << " (" << lo << ") must not exceed world.city." << hi_key
         << " (" << hi << ")";
      throw ConfigError(os.str());
    }
  };
  ordered("block_length_min", block_length_min, "block_length_max", block_length_max);
  ordered("block_depth_min", block_depth_min, "block_depth_max", block_depth_max);
  ordered("lot_frontage_min", lot_frontage_min, "lot_frontage_max", lot_frontage_max);
  ordered("tower_height_min", tower_height_min, "tower_height_max", tower_height_max);
  if (arterial_every != std::floor(arterial_every)) {
    throw ConfigError("world.city.arterial_every: expected a whole number 2 to 6, got " +
                      std::to_string(arterial_every));
  }
  if (parking_garage_share + surface_lot_share > 0.3) {
    throw ConfigError("world.city.parking_garage_share + surface_lot_share: expected at most 0.3");
  }
}

const char* toString(WorldType t) { return t == WorldType::kCity ? "city" : "suburb"; }

bool parseWorldType(const std::string& s, WorldType* out) {
  if (s == "suburb")
    *out = WorldType::kSuburb;
  else if (s == "city")
    *out = WorldType::kCity;
  else
    return false;
  return true;
}

namespace {

// Moves each edge of a convex counter-clockwise quadrilateral inwards by its own distance
// (by[i] for the edge from vertex i to vertex i+1) and returns the inner quadrilateral.
Polygon insetEdges(const Polygon& poly, const double by[4]) {
  const auto& v = poly.vertices();
  std::vector<Vec2> out;
  for (int i = 0; i < 4; ++i) {
    const int prev = (i + 3) % 4;
    const Vec2 d0 = (v[i] - v[prev]).normalized(), d1 = (v[(i + 1) % 4] - v[i]).normalized();
    const Vec2 p0 = v[prev] + by[prev] * Vec2(-d0.y(), d0.x());
    const Vec2 p1 = v[i] + by[i] * Vec2(-d1.y(), d1.x());
    const double den = geometry::cross2(d0, d1);
    const double t = std::abs(den) < 1e-12 ? 0.0 : geometry::cross2(p1 - p0, d1) / den;
    out.push_back(p0 + t * d0);
  }
  return Polygon(out);
}

// Distance from p to the line through a and b.
double lineDistance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 d = (b - a).normalized();
  return std::abs(geometry::cross2(d, p - a));
}

class CityBuilder {
 public:
  CityBuilder(const WorldParams& p, std::vector<Entity>* entities, std::vector<ParkingSlot>* slots)
      : p_(p),
        c_(p.city),
        rng_(deriveSeed(p.seed, 0x43495459ULL)),
        entities_(entities),
        slots_(slots) {}

  void build(std::vector<StreetNode>* nodes, std::vector<StreetEdge>* edges,
             std::vector<Block>* blocks, geometry::Aabb2* bounds) {
    buildGrid(nodes, edges, bounds);
    buildBlocks(*nodes, blocks);
    for (const auto& b : *blocks) buildLots(b);
    chooseTowers();
    for (const auto& b : *blocks) buildFurniture(b, *nodes);
    buildKerbSlots(*nodes, *edges, *blocks);
    parkCars();
  }

 private:
  int addEntity(EntityClass cls, const std::string& prefix, const Vec3& bottom, double yaw,
                const Vec3& size, Attributes attrs, int block) {
    return world_entities::appendEntity(entities_, &counters_, cls, prefix, bottom, yaw, size,
                                        std::move(attrs), block);
  }

  // Street positions along one axis: n gaps drawn in [lo, hi] and scaled to the extent, redrawn
  // until every scaled gap stays within [lo, hi] (equal gaps after 200 tries).
  std::vector<double> positions(double extent, double lo, double hi) {
    const int n = std::max(1, static_cast<int>(std::lround(extent / (0.5 * (lo + hi)))));
    std::vector<double> gaps(static_cast<std::size_t>(n), extent / n);
    for (int attempt = 0; attempt < 200; ++attempt) {
      std::vector<double> g;
      double total = 0.0;
      for (int i = 0; i < n; ++i) {
        const double v = rng_.uniform(lo, hi);
        g.push_back(v);
        total += v;
      }
      bool ok = true;
      for (double& v : g) {
        v *= extent / total;
        ok = ok && v >= lo && v <= hi;
      }
      if (ok) {
        gaps = g;
        break;
      }
    }
    std::vector<double> out{-0.5 * extent};
    for (double g : gaps) out.push_back(out.back() + g);
    out.back() = 0.5 * extent;
    return out;
  }

  bool arterial(int i) const { return i % static_cast<int>(c_.arterial_every) == 1; }

  void buildGrid(std::vector<StreetNode>* nodes, std::vector<StreetEdge>* edges,
                 geometry::Aabb2* bounds) {
    xs_ = positions(p_.extent_x, c_.block_length_min, c_.block_length_max);
    ys_ = positions(p_.extent_y, c_.block_depth_min, c_.block_depth_max);
    nx_ = static_cast<int>(xs_.size());
    ny_ = static_cast<int>(ys_.size());
    for (int j = 0; j < ny_; ++j) {
      for (int i = 0; i < nx_; ++i) {
        Vec2 pos(xs_[i], ys_[j]);
        if (i > 0 && j > 0 && i < nx_ - 1 && j < ny_ - 1) {
          const double jx = rng_.uniform(-c_.intersection_jitter, c_.intersection_jitter);
          const double jy = rng_.uniform(-c_.intersection_jitter, c_.intersection_jitter);
          pos += Vec2(jx, jy);
        }
        nodes->push_back({Vec2(roundMilli(pos.x()), roundMilli(pos.y()))});
      }
    }
    bounds->min = Vec2(xs_.front(), ys_.front());
    bounds->max = Vec2(xs_.back(), ys_.back());
    auto addEdge = [&](int a, int b, bool art, const std::string& name, const std::string& from,
                       const std::string& to) {
      StreetEdge e;
      e.a = a;
      e.b = b;
      e.width = art ? c_.arterial_width : c_.local_width;
      e.name = name;
      const Vec2 pa = (*nodes)[a].position, pb = (*nodes)[b].position;
      const Vec2 mid = 0.5 * (pa + pb), d = pb - pa;
      Attributes attrs;
      attrs.set("name", name);
      attrs.set("between", from + " and " + to);
      attrs.set("road", std::string(art ? "arterial" : "local"));
      attrs.set("lanes", static_cast<std::int64_t>(art ? 4 : 2));
      e.entity =
          addEntity(EntityClass::kStreet, "street", Vec3(mid.x(), mid.y(), -0.1),
                    std::atan2(d.y(), d.x()), Vec3(d.norm() + e.width, e.width, 0.1), attrs, -1);
      edges->push_back(e);
    };
    for (int j = 0; j < ny_; ++j) {
      const std::string name = catalog::streetName(false, j);
      for (int i = 0; i + 1 < nx_; ++i) {
        addEdge(j * nx_ + i, j * nx_ + i + 1, arterial(j), name, catalog::streetName(true, i),
                catalog::streetName(true, i + 1));
      }
    }
    for (int i = 0; i < nx_; ++i) {
      const std::string name = catalog::streetName(true, i);
      for (int j = 0; j + 1 < ny_; ++j) {
        addEdge(j * nx_ + i, (j + 1) * nx_ + i, arterial(i), name, catalog::streetName(false, j),
                catalog::streetName(false, j + 1));
      }
    }
  }

  // Widths of the streets on sides 0..3 (south, east, north, west) of block (i, j).
  void sideWidths(int i, int j, double w[4]) const {
    w[0] = arterial(j) ? c_.arterial_width : c_.local_width;
    w[1] = arterial(i + 1) ? c_.arterial_width : c_.local_width;
    w[2] = arterial(j + 1) ? c_.arterial_width : c_.local_width;
    w[3] = arterial(i) ? c_.arterial_width : c_.local_width;
  }

  void buildBlocks(const std::vector<StreetNode>& nodes, std::vector<Block>* blocks) {
    for (int j = 0; j + 1 < ny_; ++j) {
      for (int i = 0; i + 1 < nx_; ++i) {
        Block b;
        b.index = static_cast<int>(blocks->size());
        char name[32];
        std::snprintf(name, sizeof(name), "block_%02d", b.index + 1);
        b.name = name;
        b.outline =
            Polygon({nodes[j * nx_ + i].position, nodes[j * nx_ + i + 1].position,
                     nodes[(j + 1) * nx_ + i + 1].position, nodes[(j + 1) * nx_ + i].position});
        double w[4], in[4], walk[4];
        sideWidths(i, j, w);
        for (int s = 0; s < 4; ++s) {
          in[s] = 0.5 * w[s] + c_.sidewalk_width;
          walk[s] = 0.5 * w[s] + 0.5 * c_.sidewalk_width;
        }
        b.interior = insetEdges(b.outline, in);
        b.sidewalk = insetEdges(b.outline, walk).vertices();
        for (auto& v : b.sidewalk) v = Vec2(roundMilli(v.x()), roundMilli(v.y()));
        b.sidewalk.push_back(b.sidewalk.front());
        blocks->push_back(std::move(b));
      }
    }
  }

  // Two rows of lots facing the block's longer pair of sides, back to back across a service
  // alley along the block's midline.
  void buildLots(const Block& block) {
    const auto& v = block.interior.vertices();
    const int bi = block.index % (nx_ - 1), bj = block.index / (nx_ - 1);
    const double len02 = (v[1] - v[0]).norm() + (v[3] - v[2]).norm();
    const double len13 = (v[2] - v[1]).norm() + (v[0] - v[3]).norm();
    const int front = len02 >= len13 ? 0 : 1;  // sides front and front + 2 carry the lots
    const int other = front + 2;
    const double across = std::min({lineDistance(v[other], v[front], v[front + 1]),
                                    lineDistance(v[(other + 1) % 4], v[front], v[front + 1])});
    const bool alley = across - c_.alley_width >= 2 * 18.0;
    const double depth = 0.5 * (across - (alley ? c_.alley_width : 0.0)) - 0.2;
    if (depth < 10.0) return;
    if (alley) {
      // The alley runs from kerb to kerb along the midline between the two fronts.
      const Vec2 m0 = 0.5 * (v[front] + v[(other + 1) % 4]);
      const Vec2 m1 = 0.5 * (v[front + 1] + v[other]);
      const Vec2 d = (m1 - m0).normalized();
      const Vec2 a = m0 - c_.sidewalk_width * d, b = m1 + c_.sidewalk_width * d;
      const Vec2 mid = 0.5 * (a + b);
      Attributes aa;
      aa.set("name", block.name + " alley");
      addEntity(EntityClass::kAlley, "alley", Vec3(mid.x(), mid.y(), -0.1),
                std::atan2(d.y(), d.x()), Vec3((b - a).norm(), c_.alley_width, 0.1), aa,
                block.index);
    }
    const int street_index[4] = {bj, bi + 1, bj + 1, bi};
    for (int s : {front, other}) {
      const std::string street = catalog::streetName(s % 2 == 1, street_index[s]);
      const Vec2 a = v[s], b = v[(s + 1) % 4];
      const double len = (b - a).norm();
      const Vec2 u = (b - a) / len;
      const Vec2 n(-u.y(), u.x());  // into the block
      double start = 0.3;
      const double end = len - 0.3;
      while (end - start >= c_.lot_frontage_min) {
        double w = rng_.uniform(c_.lot_frontage_min, c_.lot_frontage_max);
        if (end - start - w < c_.lot_frontage_min) w = std::min(end - start, c_.lot_frontage_max);
        const Vec2 o = a + start * u;
        // Keep only lots whose corners lie inside the (slightly skewed) interior.
        bool inside = true;
        const std::array<Vec2, 4> corners = {
            Vec2(o + 0.1 * u + 0.1 * n), Vec2(o + (w - 0.1) * u + 0.1 * n),
            Vec2(o + (w - 0.1) * u + (depth - 0.1) * n), Vec2(o + 0.1 * u + (depth - 0.1) * n)};
        for (const Vec2& q : corners) {
          inside = inside && block.interior.contains(q);
        }
        if (inside) buildLot(block, street, o, u, n, w, depth);
        start += w;
      }
    }
  }

  void buildLot(const Block& block, const std::string& street, const Vec2& o, const Vec2& u,
                const Vec2& n, double w, double depth) {
    auto at = [&](double du, double dv) { return o + du * u + dv * n; };
    const double yaw_in = std::atan2(n.y(), n.x());
    const int number = 2 * (++numbers_) + 100;
    const double r = rng_.unit();
    if (r < c_.surface_lot_share) {
      // A surface car park: a row of stalls along the front and one along the back.
      const Vec2 lc = at(0.5 * w, 0.5 * depth);
      Attributes la;
      la.set("material", std::string("asphalt"));
      la.set("address", std::to_string(number) + " " + street);
      addEntity(EntityClass::kParkingLot, "parking_lot", Vec3(lc.x(), lc.y(), 0.0), yaw_in,
                Vec3(depth, w, 0.05), la, block.index);
      const double stall = 2.7;
      const int stalls = static_cast<int>((w - 1.0) / stall);
      for (int row = 0; row < 2 && depth >= 12.0; ++row) {
        const double dv = row == 0 ? 3.0 : depth - 3.0;
        for (int k = 0; k < stalls; ++k) {
          const Vec2 c = at(0.5 * w + (k - 0.5 * (stalls - 1)) * stall, dv);
          ParkingSlot s;
          s.position = Vec2(roundMilli(c.x()), roundMilli(c.y()));
          const bool nose_in = rng_.bernoulli(0.5);
          s.yaw =
              roundMilli(geometry::wrapPi(yaw_in + (nose_in == (row == 0) ? 0.0 : geometry::kPi)));
          s.ground_z = 0.05;
          s.driveway = true;  // off-street
          s.block = block.index;
          slots_->push_back(s);
        }
      }
      return;
    }
    const double gap = rng_.uniform(0.2, 1.0);
    const double setback = rng_.bernoulli(0.7) ? 0.0 : rng_.uniform(0.5, 2.5);
    const double bd = std::max(8.0, depth * rng_.uniform(0.8, 1.0) - setback);
    const double bw = w - gap;
    const Vec2 c = at(0.5 * w, setback + 0.5 * bd);
    Attributes a;
    if (r < c_.surface_lot_share + c_.parking_garage_share) {
      const int levels = static_cast<int>(rng_.uniformInt(3, 6));
      a.set("color", std::string("grey"));
      a.set("storeys", static_cast<std::int64_t>(levels));
      a.set("address", std::to_string(number) + " " + street);
      addEntity(EntityClass::kParkingGarage, "parking_garage", Vec3(c.x(), c.y(), 0.0), yaw_in,
                Vec3(bd, bw, levels * 3.0), a, block.index);
      return;
    }
    // Lognormal storey count (median c_.median_storeys), below tower height.
    const double z = rng_.normal(0.0, 1.0);
    const int max_storeys =
        static_cast<int>(std::floor((c_.tower_height_min - 1.0) / c_.storey_height));
    const int storeys = std::clamp(
        static_cast<int>(std::lround(c_.median_storeys * std::exp(c_.storeys_sigma * z))), 2,
        max_storeys);
    a.set("color", catalog::pick(rng_, facadeColors()));
    a.set("storeys", static_cast<std::int64_t>(storeys));
    a.set("address", std::to_string(number) + " " + street);
    a.set("use", std::string(storeys <= 3 && rng_.bernoulli(0.5) ? "retail" : "mixed"));
    buildings_.push_back(addEntity(EntityClass::kBuilding, "building", Vec3(c.x(), c.y(), 0.0),
                                   yaw_in, Vec3(bd, bw, storeys * c_.storey_height), a,
                                   block.index));
  }

  static const std::vector<std::string>& facadeColors() {
    static const std::vector<std::string> k = {"white", "beige", "grey", "brick", "brown", "blue"};
    return k;
  }

  // round(tower_share * buildings) buildings become towers: those within downtown_radius of the
  // centre in a random order, then (when the core holds too few) the nearest others.
  void chooseTowers() {
    const int k =
        static_cast<int>(std::lround(c_.tower_share * static_cast<double>(buildings_.size())));
    std::vector<std::pair<double, int>> order;
    for (int e : buildings_) {
      const double d = (*entities_)[static_cast<std::size_t>(e)].box.center2().norm();
      const double key = rng_.unit();
      order.push_back({d <= c_.downtown_radius ? key : 1.0 + d, e});
    }
    std::sort(order.begin(), order.end());
    for (int t = 0; t < k && t < static_cast<int>(order.size()); ++t) {
      Entity& e = (*entities_)[static_cast<std::size_t>(order[t].second)];
      const int lo = static_cast<int>(std::ceil(c_.tower_height_min / c_.storey_height));
      const int hi =
          std::max(lo, static_cast<int>(std::floor(c_.tower_height_max / c_.storey_height)));
      const int storeys = static_cast<int>(rng_.uniformInt(lo, hi));
      e.attributes.set("storeys", static_cast<std::int64_t>(storeys));
      e.attributes.set("use", std::string("office_tower"));
      const Vec3 bottom(e.box.center.x(), e.box.center.y(), 0.0);
      e.box =
          boxFromPose(bottom, e.box.yaw,
                      Vec3(e.box.size.x(), e.box.size.y(), roundMilli(storeys * c_.storey_height)));
    }
  }

  // Along each side's sidewalk: lamp posts, street trees (local streets), a bench now and then,
  // a bus stop on arterials; traffic-light masts at the corners of arterial intersections.
  void buildFurniture(const Block& block, const std::vector<StreetNode>& nodes) {
    const int bi = block.index % (nx_ - 1), bj = block.index / (nx_ - 1);
    double w[4], kerb[4];
    sideWidths(bi, bj, w);
    for (int s = 0; s < 4; ++s) kerb[s] = 0.5 * w[s] + 0.6;  // 0.6 m in from the kerb
    const Polygon line = insetEdges(block.outline, kerb);
    const auto& v = line.vertices();
    const int corner_node[4] = {bj * nx_ + bi, bj * nx_ + bi + 1, (bj + 1) * nx_ + bi + 1,
                                (bj + 1) * nx_ + bi};
    (void)nodes;
    for (int s = 0; s < 4; ++s) {
      const Vec2 a = v[s], b = v[(s + 1) % 4];
      const double len = (b - a).norm();
      const Vec2 u = (b - a) / len, n(-u.y(), u.x());
      const double yaw = std::atan2(u.y(), u.x());
      const bool art = w[s] >= c_.arterial_width - 1e-9;
      auto point = [&](double along, double in) { return a + along * u + in * n; };
      std::vector<double> used;  // positions taken along this side
      // A position drawn in [lo, hi], kept (and taken) when `gap` from every taken one.
      auto freeSpot = [&](double lo, double hi, double gap) -> std::optional<double> {
        const double t = rng_.uniform(lo, hi);
        for (double q : used) {
          if (std::abs(q - t) <= gap) return std::nullopt;
        }
        used.push_back(t);
        return t;
      };
      for (double t = 0.5 * c_.lamp_spacing; t < len - 4.0; t += c_.lamp_spacing) {
        const Vec2 p = point(t, 0.0);
        Attributes la;
        la.set("color", std::string("grey"));
        addEntity(EntityClass::kLampPost, "lamp_post", Vec3(p.x(), p.y(), 0.0), yaw,
                  Vec3(0.3, 0.3, 8.0), la, block.index);
        used.push_back(t);
      }
      if (!art) {
        for (double t = 6.0; t < len - 6.0; t += c_.tree_spacing) {
          bool clear = true;
          for (double q : used) clear = clear && std::abs(q - t) > 3.0;
          if (!clear) continue;
          const double diam = rng_.uniform(2.4, 3.6);
          const double h = rng_.uniform(6.0, 10.0);
          const Vec2 p = point(t, 0.3);
          Attributes ta;
          ta.set("species", catalog::pick(rng_, catalog::treeSpecies()));
          ta.set("foliage", std::string("leafy"));
          addEntity(EntityClass::kStreetTree, "street_tree", Vec3(p.x(), p.y(), 0.0), yaw,
                    Vec3(diam, diam, h), ta, block.index);
          used.push_back(t);
        }
      } else if (len > 40.0 && rng_.bernoulli(c_.bus_stop_probability)) {
        if (const auto t = freeSpot(15.0, len - 15.0, 4.0)) {
          const Vec2 p = point(*t, 0.3);
          const int street[4] = {bj, bi + 1, bj + 1, bi};
          Attributes ba;
          ba.set("name", catalog::streetName(s % 2 == 1, street[s]) + " stop");
          addEntity(EntityClass::kBusStop, "bus_stop", Vec3(p.x(), p.y(), 0.0), yaw,
                    Vec3(4.0, 1.1, 2.6), ba, block.index);
        }
      }
      if (len > 30.0 && rng_.bernoulli(c_.bench_probability)) {
        if (const auto t = freeSpot(10.0, len - 10.0, 3.5)) {
          const Vec2 p = point(*t, 0.2);
          Attributes ba;
          ba.set("color", std::string("brown"));
          addEntity(EntityClass::kBench, "bench", Vec3(p.x(), p.y(), 0.0), yaw, Vec3(1.8, 0.6, 0.9),
                    ba, block.index);
        }
      }
      // A traffic-light mast at this corner when an arterial crosses here.
      const int node_i = corner_node[s] % nx_, node_j = corner_node[s] / nx_;
      const bool crossing_arterial = arterial(node_i) || arterial(node_j);
      const bool interior_node = node_i > 0 && node_j > 0 && node_i < nx_ - 1 && node_j < ny_ - 1;
      if (crossing_arterial && interior_node) {
        Attributes ta;
        ta.set("color", std::string("black"));
        addEntity(EntityClass::kTrafficLight, "traffic_light", Vec3(a.x(), a.y(), 0.0), yaw,
                  Vec3(0.4, 0.4, 6.0), ta, block.index);
      }
    }
  }

  // Kerb slots every 6.5 m on both sides of local streets, clear of the intersections, the
  // alley mouths and the street furniture at the kerb.
  void buildKerbSlots(const std::vector<StreetNode>& nodes, const std::vector<StreetEdge>& edges,
                      const std::vector<Block>& blocks) {
    geometry::OccluderIndex keep_clear(20.0);
    for (const auto& e : *entities_) {
      if (e.cls == EntityClass::kAlley || e.cls == EntityClass::kStreetTree ||
          e.cls == EntityClass::kBusStop || e.cls == EntityClass::kTrafficLight ||
          e.cls == EntityClass::kLampPost) {
        keep_clear.add(e.box);
      }
    }
    keep_clear.build();
    const double corner = 0.5 * c_.arterial_width + 8.0;
    world_entities::addKerbSlots(
        nodes, edges, blocks, keep_clear, 3.2, 6.5,
        [&](const StreetEdge& e) { return e.width >= c_.arterial_width - 1e-9 ? -1.0 : corner; },
        slots_);
  }

  void parkCars() {
    world_entities::parkCars(rng_, c_.lot_parking_probability, c_.street_parking_probability,
                             slots_, entities_, &counters_);
  }

  const WorldParams& p_;
  const CityParams& c_;
  Rng rng_;
  std::vector<Entity>* entities_;
  std::vector<ParkingSlot>* slots_;
  std::vector<double> xs_, ys_;
  int nx_ = 0, ny_ = 0;
  world_entities::EntityCounters counters_;
  int numbers_ = 0;
  std::vector<int> buildings_;
};

}  // namespace

void buildCityWorld(const WorldParams& params, World* world) {
  CityBuilder builder(params, &world->entities_, &world->slots_);
  builder.build(&world->nodes_, &world->edges_, &world->blocks_, &world->bounds_);
}

}  // namespace hameritt::scenario
