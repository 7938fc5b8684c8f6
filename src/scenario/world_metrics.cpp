#include "hameritt/scenario/world_metrics.h"

#include <algorithm>
#include <cmath>

#include "hameritt/geometry/segment.h"
#include "hameritt/scenario/json_writer.h"
#include "hameritt/scenario/rng.h"

namespace hameritt::scenario {

using geometry::Vec2;
using geometry::Vec3;

namespace {

bool isBuilding(EntityClass c) {
  return c == EntityClass::kBuilding || c == EntityClass::kParkingGarage ||
         c == EntityClass::kHouse;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Footprint union of the building classes (and suburban garages) by rasterisation.
double planFraction(const World& world, double cell) {
  const auto b = world.bounds();
  const int nx = static_cast<int>(std::ceil((b.max.x() - b.min.x()) / cell));
  const int ny = static_cast<int>(std::ceil((b.max.y() - b.min.y()) / cell));
  std::vector<unsigned char> covered(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny),
                                     0);
  for (const auto& e : world.entities()) {
    if (!isBuilding(e.cls) && e.cls != EntityClass::kGarage) continue;
    const geometry::Aabb2 r = e.box.bounds2();
    const int x0 = std::max(0, static_cast<int>(std::floor((r.min.x() - b.min.x()) / cell)));
    const int x1 = std::min(nx - 1, static_cast<int>(std::floor((r.max.x() - b.min.x()) / cell)));
    const int y0 = std::max(0, static_cast<int>(std::floor((r.min.y() - b.min.y()) / cell)));
    const int y1 = std::min(ny - 1, static_cast<int>(std::floor((r.max.y() - b.min.y()) / cell)));
    const geometry::Polygon fp = e.box.footprint();
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const Vec2 c(b.min.x() + (x + 0.5) * cell, b.min.y() + (y + 0.5) * cell);
        if (fp.contains(c)) covered[static_cast<std::size_t>(y) * nx + x] = 1;
      }
    }
  }
  std::size_t n = 0;
  for (unsigned char c : covered) n += c;
  return static_cast<double>(n) / static_cast<double>(covered.size());
}

// A point of the block sidewalk rings, uniform by length.
class SidewalkSampler {
 public:
  explicit SidewalkSampler(const World& world) {
    for (const auto& b : world.blocks()) {
      for (std::size_t i = 0; i + 1 < b.sidewalk.size(); ++i) {
        segments_.push_back({b.sidewalk[i], b.sidewalk[i + 1]});
        total_ += (b.sidewalk[i + 1] - b.sidewalk[i]).norm();
        cumulative_.push_back(total_);
      }
    }
  }
  bool empty() const { return segments_.empty(); }
  Vec2 draw(Rng& rng) const {
    const double s = rng.uniform(0.0, total_);
    const auto it = std::lower_bound(cumulative_.begin(), cumulative_.end(), s);
    const std::size_t i = std::min<std::size_t>(it - cumulative_.begin(), segments_.size() - 1);
    const double start = i == 0 ? 0.0 : cumulative_[i - 1];
    const auto& [a, b] = segments_[i];
    const double len = (b - a).norm();
    return len > 0 ? a + (b - a) * ((s - start) / len) : a;
  }

 private:
  std::vector<std::pair<Vec2, Vec2>> segments_;
  std::vector<double> cumulative_;
  double total_ = 0.0;
};

bool insideOccluder(const World& world, const Vec3& p) {
  const auto& occ = world.occluders();
  for (int i : occ.candidates(geometry::Aabb2{p.head<2>(), p.head<2>()})) {
    const auto& [c, s] = occ.trig(i);
    if (occ.box(i).contains(p, c, s)) return true;
  }
  return false;
}

double round4(double v) { return std::round(v * 1e4) / 1e4; }

// Widens [*lo, *hi] to hold v (the first value sets both, `*first` is then cleared).
void widen(double v, double* lo, double* hi, bool* first) {
  if (*first) {
    *lo = *hi = v;
    *first = false;
  }
  *lo = std::min(*lo, v);
  *hi = std::max(*hi, v);
}

}  // namespace

double skyViewFactor(const World& world, const Vec3& p, int rays, double length) {
  // Stratified cosine-weighted directions: rings of equal solid-angle weight in sin^2 of the
  // zenith angle, azimuths offset per ring (a Fibonacci-like spiral).
  int clear = 0;
  const double golden = geometry::kPi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < rays; ++k) {
    const double u = (k + 0.5) / rays;  // sin^2(zenith)
    const double sin_t = std::sqrt(u), cos_t = std::sqrt(1.0 - u);
    const double phi = golden * k;
    const Vec3 d(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
    if (world.occluders().clear(p, p + length * d)) ++clear;
  }
  return rays > 0 ? static_cast<double>(clear) / rays : 0.0;
}

WorldMetrics measureWorld(const World& world, const MetricsSettings& s) {
  WorldMetrics m;
  const WorldParams& p = world.params();
  m.type = toString(p.type);
  m.tile_area_km2 = p.extent_x * p.extent_y / 1e6;
  m.blocks = static_cast<int>(world.blocks().size());
  m.blocks_per_km2 = m.blocks / m.tile_area_km2;
  bool first = true;
  for (const auto& b : world.blocks()) {
    const auto& v = b.outline.vertices();
    const double len = 0.5 * ((v[1] - v[0]).norm() + (v[2] - v[3]).norm());
    const double dep = 0.5 * ((v[3] - v[0]).norm() + (v[2] - v[1]).norm());
    bool first_depth = first;
    widen(len, &m.block_length_min, &m.block_length_max, &first);
    widen(dep, &m.block_depth_min, &m.block_depth_max, &first_depth);
  }
  m.arterial_width = world.maxStreetWidth();
  m.local_width = m.arterial_width;
  for (const auto& e : world.edges()) {
    m.local_width = std::min(m.local_width, e.width);
    if (e.width >= 20.0)
      ++m.arterial_edges;
    else
      ++m.local_edges;
  }
  m.sidewalk_width = world.sidewalkWidth();
  std::vector<double> storeys, frontage;
  int towers = 0;
  bool first_tower = true, first_alley = true;
  for (const auto& e : world.entities()) {
    switch (e.cls) {
      case EntityClass::kAlley:
        ++m.alleys;
        widen(e.box.size.y(), &m.alley_width_min, &m.alley_width_max, &first_alley);
        break;
      case EntityClass::kParkingGarage:
        ++m.parking_garages;
        break;
      case EntityClass::kParkingLot:
        ++m.parking_lots;
        break;
      case EntityClass::kLampPost:
        ++m.lamp_posts;
        break;
      case EntityClass::kStreetTree:
        ++m.street_trees;
        break;
      case EntityClass::kBench:
        ++m.benches;
        break;
      case EntityClass::kBusStop:
        ++m.bus_stops;
        break;
      case EntityClass::kTrafficLight:
        ++m.traffic_lights;
        break;
      case EntityClass::kCar:
        ++m.parked_cars;
        break;
      default:
        break;
    }
    if (!isBuilding(e.cls)) continue;
    ++m.buildings;
    if (e.cls != EntityClass::kParkingGarage) {
      storeys.push_back(static_cast<double>(e.attributes.integer("storeys", 1)));
    }
    if (e.cls == EntityClass::kBuilding) frontage.push_back(e.box.size.y());
    if (e.box.size.z() >= 60.0) {
      ++towers;
      widen(e.box.size.z(), &m.tower_height_min, &m.tower_height_max, &first_tower);
    }
  }
  for (const auto& sl : world.slots()) m.kerb_slots += sl.edge >= 0 ? 1 : 0;
  m.buildings_per_km2 = m.buildings / m.tile_area_km2;
  m.median_storeys = median(storeys);
  m.tower_share = m.buildings ? static_cast<double>(towers) / m.buildings : 0.0;
  if (!frontage.empty()) {
    m.frontage_min = *std::min_element(frontage.begin(), frontage.end());
    m.frontage_max = *std::max_element(frontage.begin(), frontage.end());
  }
  m.plan_fraction = planFraction(world, s.plan_cell);

  // P_LOS(h): a sidewalk point, then an observer h m up, uniform in the disc of radius
  // los_radius around it, inside the bounds and outside every occluder.
  Rng rng(deriveSeed(s.seed, 0x4C4F53ULL));
  const SidewalkSampler walks(world);
  const auto bounds = world.bounds();
  for (double h : s.los_heights) {
    LosMeasure lm;
    lm.height = h;
    int clear = 0;
    for (int k = 0; k < s.los_samples && !walks.empty(); ++k) {
      const Vec2 w = walks.draw(rng);
      const Vec3 target(w.x(), w.y(), s.sidewalk_point_z);
      Vec3 eye;
      for (int attempt = 0; attempt < 100; ++attempt) {
        const double r = s.los_radius * std::sqrt(rng.unit());
        const double a = rng.uniform(-geometry::kPi, geometry::kPi);
        eye = Vec3(w.x() + r * std::cos(a), w.y() + r * std::sin(a), h);
        if (bounds.contains(eye.head<2>()) && !insideOccluder(world, eye)) break;
      }
      ++lm.samples;
      if (world.occluders().clear(eye, target)) ++clear;
    }
    lm.probability = lm.samples ? static_cast<double>(clear) / lm.samples : 0.0;
    m.los.push_back(lm);
  }

  // Sky-view factor at street level: pedestrian points on the sidewalk rings, 1.5 m up.
  std::vector<double> svf;
  for (int k = 0; k < s.svf_points && !walks.empty(); ++k) {
    const Vec2 q = walks.draw(rng);
    const Vec3 pt(q.x(), q.y(), s.svf_point_z);
    if (insideOccluder(world, pt)) continue;
    svf.push_back(skyViewFactor(world, pt, s.svf_rays, s.svf_ray_length));
  }
  m.svf_points = static_cast<int>(svf.size());
  m.svf_median = median(svf);
  return m;
}

double losAt(const WorldMetrics& m, double height) {
  for (const auto& l : m.los) {
    if (std::abs(l.height - height) < 1e-9) return l.probability;
  }
  return -1.0;
}

std::string metricsJson(const WorldMetrics& m) {
  JsonWriter w;
  w.beginObject();
  w.key("type").value(m.type);
  w.key("tile_area_km2").value(round4(m.tile_area_km2));
  w.key("blocks").value(m.blocks).key("blocks_per_km2").value(round4(m.blocks_per_km2));
  w.key("block_length_m").numbers({round4(m.block_length_min), round4(m.block_length_max)});
  w.key("block_depth_m").numbers({round4(m.block_depth_min), round4(m.block_depth_max)});
  w.key("arterial_edges").value(m.arterial_edges).key("local_edges").value(m.local_edges);
  w.key("widest_street_m").value(round4(m.arterial_width));
  w.key("narrowest_street_m").value(round4(m.local_width));
  w.key("alleys").value(m.alleys);
  w.key("alley_width_m").numbers({round4(m.alley_width_min), round4(m.alley_width_max)});
  w.key("sidewalk_width_m").value(round4(m.sidewalk_width));
  w.key("buildings").value(m.buildings).key("buildings_per_km2").value(round4(m.buildings_per_km2));
  w.key("building_frontage_m").numbers({round4(m.frontage_min), round4(m.frontage_max)});
  w.key("plan_fraction").value(round4(m.plan_fraction));
  w.key("median_storeys").value(round4(m.median_storeys));
  w.key("tower_share").value(round4(m.tower_share));
  w.key("tower_height_m").numbers({round4(m.tower_height_min), round4(m.tower_height_max)});
  w.key("parking_garages").value(m.parking_garages).key("parking_lots").value(m.parking_lots);
  w.key("kerb_slots").value(m.kerb_slots).key("parked_cars").value(m.parked_cars);
  w.key("lamp_posts").value(m.lamp_posts).key("street_trees").value(m.street_trees);
  w.key("benches").value(m.benches).key("bus_stops").value(m.bus_stops);
  w.key("traffic_lights").value(m.traffic_lights);
  w.key("p_los").beginArray();
  for (const auto& l : m.los) {
    w.beginObject();
    w.key("height_m").value(l.height).key("probability").value(round4(l.probability));
    w.key("samples").value(l.samples);
    w.endObject();
  }
  w.endArray();
  w.key("svf_median").value(round4(m.svf_median)).key("svf_points").value(m.svf_points);
  w.endObject();
  return w.str();
}

}  // namespace hameritt::scenario
