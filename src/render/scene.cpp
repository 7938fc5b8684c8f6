#include "scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <unordered_map>

#include "hameritt/scenario/bounded_json.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/trajectory.h"

namespace hameritt::render {

namespace {

using scenario::EntityClass;

std::uint32_t packRgb8(int r, int g, int b) {
  return static_cast<std::uint32_t>(r) | (static_cast<std::uint32_t>(g) << 8) |
         (static_cast<std::uint32_t>(b) << 16) | (255u << 24);
}

std::uint32_t packLinearHalf(const Eigen::Vector3f& c) {
  auto q = [](float v) {
    return static_cast<int>(std::lround(std::clamp(0.5f * v, 0.0f, 1.0f) * 255.0f));
  };
  return packRgb8(q(c.x()), q(c.y()), q(c.z()));
}

// FNV-1a (64 bits) of a string: per-entity variation that does not depend on draw order.
std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

// FNV-1a of a string in [0, 1).
float hash01(const std::string& s) {
  return static_cast<float>((fnv1a(s) >> 40) & 0xFFFFFF) / 16777216.0f;
}

// The centre of a model's bounds placed by an instance record's rows: the bounding sphere's.
Eigen::Vector3f recordCenter(const InstanceRecord& rec, const Mesh& mesh) {
  const Eigen::Vector3f c = 0.5f * (mesh.min + mesh.max);
  Eigen::Vector3f out;
  for (int r = 0; r < 3; ++r) {
    out[r] = rec.row[r][0] * c.x() + rec.row[r][1] * c.y() + rec.row[r][2] * c.z() + rec.row[r][3];
  }
  return out;
}

// The radius of a normalized model's bounding sphere scaled to a box of `size`.
float scaledRadius(const Mesh& mesh, const Eigen::Vector3d& size) {
  return (0.5f * (mesh.max - mesh.min)).cwiseProduct(size.cast<float>()).norm();
}

// Layers of the flat ground, above the lawn at z = 0: sidewalks, then streets. Each street gets
// its own height so that where two street slabs overlap (intersections) the order is decided by
// the depth test, not by the draw order, and a ray cast agrees with the rasterizer.
constexpr double kSidewalkZ = 0.01;
double streetTopZ(int street_index) { return 0.02 + 0.001 * (street_index % 8); }
// The lawn extends this far beyond the street grid (the far clip is 2 km).
constexpr double kGroundMargin = 2000.0;
constexpr double kGroundTile = 250.0;

// Display colour (gamma 2, as the shaders use) to linear albedo.
Eigen::Vector3f srgbToLinear(int r, int g, int b) {
  auto f = [](int v) { return std::pow(static_cast<float>(v) / 255.0f, 2.0f); };
  return {f(r), f(g), f(b)};
}

Mesh groundMesh(const geometry::Aabb2& bounds) {
  const double x0 = bounds.min.x() - kGroundMargin, x1 = bounds.max.x() + kGroundMargin;
  const double y0 = bounds.min.y() - kGroundMargin, y1 = bounds.max.y() + kGroundMargin;
  const int nx = std::max(1, static_cast<int>(std::ceil((x1 - x0) / kGroundTile)));
  const int ny = std::max(1, static_cast<int>(std::ceil((y1 - y0) / kGroundTile)));
  std::vector<std::array<Eigen::Vector3f, 4>> quads;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const float xa = static_cast<float>(x0 + (x1 - x0) * i / nx);
      const float xb = static_cast<float>(x0 + (x1 - x0) * (i + 1) / nx);
      const float ya = static_cast<float>(y0 + (y1 - y0) * j / ny);
      const float yb = static_cast<float>(y0 + (y1 - y0) * (j + 1) / ny);
      quads.push_back({{{xa, ya, 0}, {xb, ya, 0}, {xb, yb, 0}, {xa, yb, 0}}});
    }
  }
  return flatMesh("ground", MaterialKind::kLawn, srgbToLinear(82, 106, 54), quads);
}

// The sidewalk rings: a strip of the given width centred on each block's closed ring (convex),
// mitred at the corners.
Mesh sidewalkMesh(const std::vector<scenario::Block>& blocks, double width) {
  const float z = static_cast<float>(kSidewalkZ);
  std::vector<std::array<Eigen::Vector3f, 4>> quads;
  for (const auto& b : blocks) {
    std::vector<geometry::Vec2> ring(b.sidewalk.begin(), b.sidewalk.end());
    if (ring.size() >= 2 && ring.front() == ring.back()) ring.pop_back();
    const std::size_t n = ring.size();
    if (n < 3) continue;
    double area = 0;
    for (std::size_t i = 0; i < n; ++i) area += geometry::cross2(ring[i], ring[(i + 1) % n]);
    if (area < 0) std::reverse(ring.begin(), ring.end());
    std::vector<geometry::Vec2> inner(n), outer(n);
    for (std::size_t i = 0; i < n; ++i) {
      const geometry::Vec2 u0 = (ring[i] - ring[(i + n - 1) % n]).normalized();
      const geometry::Vec2 u1 = (ring[(i + 1) % n] - ring[i]).normalized();
      const geometry::Vec2 n0(-u0.y(), u0.x()), n1(-u1.y(), u1.x());  // left = into the block
      const geometry::Vec2 miter = (n0 + n1).normalized();
      const double len = 0.5 * width / std::max(0.2, miter.dot(n0));
      inner[i] = ring[i] + len * miter;
      outer[i] = ring[i] - len * miter;
    }
    auto v = [z](const geometry::Vec2& p) {
      return Eigen::Vector3f(static_cast<float>(p.x()), static_cast<float>(p.y()), z);
    };
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = (i + 1) % n;
      quads.push_back({v(outer[i]), v(outer[k]), v(inner[k]), v(inner[i])});
    }
  }
  return flatMesh("sidewalks", MaterialKind::kSidewalk, srgbToLinear(188, 185, 176), quads);
}

void identityRows(float rows[3][4]) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) rows[r][c] = r == c ? 1.0f : 0.0f;
  }
}

void isometryRows(const Eigen::Isometry3d& t, float rows[3][4]) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) rows[r][c] = static_cast<float>(t.matrix()(r, c));
  }
}

std::uint32_t label(int semantic, int instance) {
  return (static_cast<std::uint32_t>(semantic) << 16) | static_cast<std::uint32_t>(instance);
}

std::string attributeError(const scenario::Entity& e, const std::string& key,
                           const std::string& expected) {
  return "entity " + e.id + ": attribute " + key + ": expected " + expected + ", got '" +
         e.attributes.str(key) + "'";
}

}  // namespace

std::vector<RooftopPart> rooftopEquipment(const scenario::Entity& e) {
  std::vector<RooftopPart> out;
  const double length = e.box.size.x(), width = e.box.size.y(), top = e.box.maxZ();
  std::uint64_t h = fnv1a(e.id);
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 32;
  const double sx = (h & 1) ? 1.0 : -1.0, sy = (h & 2) ? 1.0 : -1.0;
  const double u = static_cast<double>((h >> 8) & 255) / 255.0;
  const double v = static_cast<double>((h >> 16) & 255) / 255.0;
  const double c = std::cos(e.box.yaw), s = std::sin(e.box.yaw);
  // A box of size (a, b, height) centred at (x, y) in the building's frame, on the roof.
  auto place = [&](RooftopPart::Kind kind, double x, double y, double a, double b,
                   double height) {
    geometry::OrientedBox box;
    box.center = Eigen::Vector3d(e.box.center.x() + c * x - s * y, e.box.center.y() + s * x + c * y,
                      top + 0.5 * height);
    box.size = Eigen::Vector3d(a, b, height);
    box.yaw = e.box.yaw;
    out.push_back({kind, box});
  };
  // The offset of a part of half size `half` along a roof side of half length `side`: between
  // the centre's clearance (0.5 m) and the parapet's (0.8 m), at a fraction t of the room.
  auto offset = [](double side, double half, double t) {
    const double lo = half + 0.5, hi = side - half - 0.8;
    return lo + t * (hi - lo);
  };
  if (length >= 8.0 && width >= 6.4) {
    place(RooftopPart::Kind::kUnit, sx * offset(0.5 * length, 1.2, u), sy * offset(0.5 * width, 0.8, v), 2.4, 1.6, 1.3);
  }
  const std::int64_t storeys = e.attributes.integer("storeys", 0);
  if (storeys >= 6 && ((h >> 24) & 1) != 0 && length >= 8.0 && width >= 8.0) {
    place(RooftopPart::Kind::kTank, -sx * offset(0.5 * length, 1.3, v), -sy * offset(0.5 * width, 1.3, u), 2.6, 2.6, 3.2);
  }
  if (e.box.size.z() >= 60.0 && length >= 14.0 && width >= 10.0) {
    place(RooftopPart::Kind::kBulkhead, -sx * offset(0.5 * length, 1.8, 0.5), sy * offset(0.5 * width, 1.3, 0.5), 3.6, 2.6, 3.0);
  }
  return out;
}


bool paintColor(const std::string& name, std::uint32_t* srgb8) {
  struct Named {
    const char* name;
    int r, g, b;
  };
  // Typical paint and facade values (sRGB).
  static const Named kColors[] = {
      {"red", 158, 26, 28},     {"blue", 32, 62, 130},       {"white", 232, 232, 226},
      {"black", 24, 24, 27},    {"silver", 168, 171, 175},   {"grey", 108, 110, 114},
      {"gray", 108, 110, 114},  {"green", 38, 92, 52},       {"yellow", 222, 184, 52},
      {"beige", 214, 196, 160}, {"brick", 146, 64, 48},      {"brown", 104, 70, 44},
      {"orange", 222, 108, 30}, {"concrete", 178, 175, 166}, {"asphalt", 68, 68, 70},
  };
  for (const auto& c : kColors) {
    if (name == c.name) {
      *srgb8 = packRgb8(c.r, c.g, c.b);
      return true;
    }
  }
  return false;
}

std::uint32_t signalLamps(scenario::SignalState axis0, scenario::SignalState axis1,
                          double heading0) {
  auto lamp = [](scenario::SignalState s) -> std::uint32_t {
    switch (s) {
      case scenario::SignalState::kGreen:
        return 2;
      case scenario::SignalState::kYellow:
        return 1;
      default:
        return 0;  // red, and the other axis' protected left arrow
    }
  };
  const double turns = heading0 / (2.0 * M_PI);
  const auto h = static_cast<std::uint32_t>(
      static_cast<long>(std::lround((turns - std::floor(turns)) * 256.0)) & 255);
  const auto arrow = [](scenario::SignalState st) -> std::uint32_t {
    return st == scenario::SignalState::kLeftArrow ? 1u : 0u;
  };
  return lamp(axis0) | (lamp(axis1) << 2) | (arrow(axis0) << 4) | (arrow(axis1) << 5) | (h << 8);
}

void boxRecordRows(const geometry::OrientedBox& box, double lift, float rows[3][4]) {
  const double c = std::cos(box.yaw), s = std::sin(box.yaw);
  const double l = box.size.x(), w = box.size.y(), h = box.size.z();
  const double m[3][4] = {{c * l, -s * w, 0, box.center.x()},
                          {s * l, c * w, 0, box.center.y()},
                          {0, 0, h, box.minZ() + lift}};
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 4; ++k) rows[r][k] = static_cast<float>(m[r][k]);
  }
}

LodView::LodView(const RenderRequest& r, double max_error)
    : eye(r.world_T_optical.translation()),
      axis(r.world_T_optical.linear().col(2)),
      max_error_px(max_error) {
  const Intrinsics& k = r.intrinsics;
  // The widest ray of the image: through the corner pixel edge farthest from the principal
  // point.
  const double tx = std::max(k.cx + 0.5, k.width - 0.5 - k.cx) / k.fx;
  const double ty = std::max(k.cy + 0.5, k.height - 0.5 - k.cy) / k.fy;
  focal = std::max(k.fx, k.fy);
  max_angle = std::atan(std::sqrt(tx * tx + ty * ty));
}

int LodView::level(const SceneInstance& si, const Eigen::Vector3f& center, float radius) const {
  if (max_error_px <= 0 || si.lod_levels == 0) return 0;
  const Eigen::Vector3d v = center.cast<double>() - eye;
  const double z = v.dot(axis);
  const double z_min = z - radius;
  if (z_min <= 0) return 0;
  const double dist = v.norm();
  const double lateral = std::sqrt(std::max(0.0, dist * dist - z * z));
  const double angle =
      std::min(std::atan2(lateral, z) + std::asin(std::min(1.0, radius / dist)), max_angle);
  // Deviations grow with the level: the last one within the budget.
  const double budget = max_error_px * z_min * std::cos(angle) / focal;
  int level = 0;
  while (level < si.lod_levels && si.lod_deviation[static_cast<std::size_t>(level)] <= budget) {
    ++level;
  }
  return level;
}

int Scene::addModel(Mesh mesh) {
  models_.push_back(std::move(mesh));
  return static_cast<int>(models_.size()) - 1;
}

void Scene::loadLods(const std::string& dir,
                     const std::unordered_map<std::string, int>& file_model) {
  lods_.assign(models_.size(), {});
  const std::string path = dir + "lod.json";
  if (!std::ifstream(path)) return;  // no coarse meshes: every instance is drawn in full
  std::string text;
  try {
    text = scenario::readBoundedFile(path);
  } catch (const scenario::ConfigError& e) {
    throw RenderError(e.what());
  }
  std::set<std::string> class_meshes;
  for (const auto& [file, m] : file_model) {
    const std::string name = file.substr(0, file.size() - 4);  // without ".obj"
    if (name != "sentinel") class_meshes.insert(name);
  }
  for (const LodManifestEntry& e : parseLodManifest(text, path, dir, class_meshes)) {
    const int fine = file_model.at(e.mesh + ".obj");
    std::vector<LodLevel> levels;
    for (const LodFileLevel& lf : e.levels) {
      Mesh coarse = loadObjMesh(dir + lf.file, true);
      // The canopy of every level is scaled about the same point.
      coarse.canopy_center = models_[static_cast<std::size_t>(fine)].canopy_center;
      LodLevel level_of;
      level_of.model = addModel(std::move(coarse));
      for (int a = 0; a < 3; ++a) {
        level_of.axis_error[a] = static_cast<float>(lf.max_deviation_m / e.design_size_m[a]);
      }
      levels.push_back(level_of);
    }
    lods_[static_cast<std::size_t>(fine)] = std::move(levels);
  }
}

Scene::Scene(const scenario::World& world, const scenario::SimConfig& config,
             const std::string& models_dir)
    : config_(config) {
  const std::string dir = models_dir + "/meshes/";
  std::unordered_map<std::string, int> file_model;
  auto model = [&](const std::string& file) {
    auto it = file_model.find(file);
    if (it != file_model.end()) return it->second;
    const int m = addModel(loadObjMesh(dir + file, file != "sentinel.obj"));
    file_model[file] = m;
    return m;
  };
  // Every class mesh is loaded up front, so that a missing file fails the construction.
  for (const char* f :
       {"house_1.obj", "house_2.obj", "garage_1.obj", "garage_2.obj", "fence_wood.obj",
        "fence_vinyl.obj", "fence_chain_link.obj", "tree_deciduous.obj", "tree_pine.obj",
        "car_sedan.obj", "car_suv.obj", "car_pickup.obj", "car_hatchback.obj", "car_van.obj",
        "pedestrian.obj", "sentinel.obj", "aircraft_fixed_wing.obj", "aircraft_quadrotor.obj"}) {
    model(f);
  }
  loadLods(dir, file_model);
  procedural_.uav = model("sentinel.obj");
  procedural_.ground = addModel(groundMesh(world.bounds()));
  procedural_.sidewalks = addModel(sidewalkMesh(world.blocks(), world.sidewalkWidth()));
  procedural_.street =
      addModel(unitQuad("street", MaterialKind::kStreet, srgbToLinear(64, 65, 68)));
  procedural_.driveway =
      addModel(unitBox("driveway", MaterialKind::kPaint, Eigen::Vector3f(0.5f, 0.5f, 0.5f)));
  lods_.resize(models_.size());  // the coarse and procedural models have no levels

  foliage_ = std::clamp(config.environment.foliage, 0.0, 1.0);
  const std::size_t n_world = world.entities().size();
  aircraft_ = scenario::aircraftEntities(config);
  // + none, + uav
  const std::size_t n_total = 2 + n_world + config.entities.size() + aircraft_.size();
  if (n_total > 65536) {
    throw RenderError("scene: " + std::to_string(n_total - 1) +
                      " instances do not fit the 16-bit instance labels (at most 65535)");
  }
  entity_ids_.assign(n_total, "");
  uav_instance_ = static_cast<int>(n_total) - 1;
  entity_ids_[static_cast<std::size_t>(uav_instance_)] = "uav";

  // Ground layers: lawn and sidewalks, label "ground" with no instance.
  for (int m : {procedural_.ground, procedural_.sidewalks}) {
    SceneInstance si;
    si.model = m;
    si.semantic = kGroundSemantic;
    identityRows(si.record.row);
    si.record.label = label(kGroundSemantic, 0);
    const Mesh& mesh = models_[static_cast<std::size_t>(m)];
    si.center = 0.5f * (mesh.min + mesh.max);
    si.radius = 0.5f * (mesh.max - mesh.min).norm();
    instances_.push_back(si);
  }

  // Procedural boxes of the city classes, made on first use (a suburb scene has none).
  std::unordered_map<std::string, int> city_model;
  auto cityBox = [&](const std::string& name, MaterialKind kind, const Eigen::Vector3f& kd) {
    auto it = city_model.find(name);
    if (it != city_model.end()) return it->second;
    const int m = addModel(unitBox(name, kind, kd));
    lods_.resize(models_.size());
    city_model[name] = m;
    return m;
  };
  int street_index = 0;
  auto add = [&](const scenario::Entity& e, int instance_id, int scenario_entity, bool mover) {
    SceneInstance si;
    si.instance_id = instance_id;
    si.semantic = scenario::semanticId(e.cls);
    si.scenario_entity = scenario_entity;
    si.mover = mover;
    si.cls = e.cls;
    si.interest = hasBoundingBox(e.cls);
    si.box = e.box;
    double lift = 0.0;
    std::string color_key;
    switch (e.cls) {
      case EntityClass::kStreet:
      case EntityClass::kAlley:
        si.model = procedural_.street;
        si.convex = true;
        lift = streetTopZ(street_index++) - e.box.minZ();  // the slab's top face only
        break;
      case EntityClass::kBuilding:
        si.model = cityBox("building", MaterialKind::kFacade, Eigen::Vector3f(0.5f, 0.5f, 0.5f));
        procedural_.building = si.model;
        color_key = "color";
        {
          const std::int64_t storeys = e.attributes.integer("storeys", 0);
          si.record.canopy =
              static_cast<float>(storeys > 0 ? e.box.size.z() / static_cast<double>(storeys) : 3.5);
        }
        si.convex = true;
        break;
      case EntityClass::kParkingGarage:
        si.model =
            cityBox("parking_garage", MaterialKind::kPaint, Eigen::Vector3f(0.5f, 0.5f, 0.5f));
        color_key = "color";
        si.convex = true;
        break;
      case EntityClass::kParkingLot:
        si.model = procedural_.driveway;
        if (!paintColor("asphalt", &si.record.color)) {
          throw RenderError(attributeError(e, "material", "asphalt"));
        }
        si.convex = true;
        break;
      case EntityClass::kLampPost:
        si.model = cityBox("lamp_post", MaterialKind::kPlain, srgbToLinear(70, 72, 76));
        si.convex = true;
        break;
      case EntityClass::kTrafficLight:
        si.model = cityBox("traffic_light", MaterialKind::kSignal, srgbToLinear(30, 32, 30));
        procedural_.signal = si.model;
        si.record.color = kSignalDark;
        si.convex = true;
        break;
      case EntityClass::kBusStop:
        si.model = cityBox("bus_stop", MaterialKind::kPlain, srgbToLinear(120, 150, 170));
        si.convex = true;
        break;
      case EntityClass::kBench:
        si.model = cityBox("bench", MaterialKind::kPaint, Eigen::Vector3f(0.5f, 0.5f, 0.5f));
        color_key = "color";
        si.convex = true;
        break;
      case EntityClass::kDriveway: {
        si.model = procedural_.driveway;
        const std::string mat = e.attributes.str("material");
        if (!paintColor(mat, &si.record.color) || (mat != "concrete" && mat != "asphalt")) {
          throw RenderError(attributeError(e, "material", "concrete or asphalt"));
        }
        break;
      }
      case EntityClass::kHouse:
        si.model = model(e.attributes.integer("storeys", 1) >= 2 ? "house_2.obj" : "house_1.obj");
        color_key = "color";
        break;
      case EntityClass::kGarage:
        si.model = model(e.attributes.integer("doors", 1) >= 2 ? "garage_2.obj" : "garage_1.obj");
        color_key = "color";
        break;
      case EntityClass::kFence: {
        const std::string mat = e.attributes.str("material");
        if (mat != "wood" && mat != "vinyl" && mat != "chain_link") {
          throw RenderError(attributeError(e, "material", "wood, vinyl or chain_link"));
        }
        si.model = model("fence_" + mat + ".obj");
        color_key = "color";
        break;
      }
      case EntityClass::kTree:
      case EntityClass::kStreetTree: {
        const std::string species = e.attributes.str("species");
        si.model = model(species == "pine" ? "tree_pine.obj" : "tree_deciduous.obj");
        // Foliage density: canopies scale about their centre by 0.35 + 0.65 * foliage, a
        // "sparse" tree by a further 0.85; at density 0 only trunks are drawn.
        si.record.canopy = static_cast<float>(
            (0.35 + 0.65 * foliage_) * (e.attributes.str("foliage") == "sparse" ? 0.85 : 1.0));
        Eigen::Vector3f tint(0.85f, 1.0f, 0.8f);  // oak
        if (species == "maple") tint = Eigen::Vector3f(1.0f, 0.92f, 0.72f);
        if (species == "birch") tint = Eigen::Vector3f(1.15f, 1.2f, 0.75f);
        if (species == "pine") tint = Eigen::Vector3f(0.62f, 0.82f, 0.78f);
        tint *= 0.9f + 0.2f * hash01(e.id);
        si.record.color = packLinearHalf(tint);
        break;
      }
      case EntityClass::kCar: {
        const std::string vc = e.attributes.str("vehicle_class");
        if (vc != "sedan" && vc != "suv" && vc != "pickup" && vc != "hatchback" && vc != "van") {
          throw RenderError(
              attributeError(e, "vehicle_class", "sedan, suv, pickup, hatchback or van"));
        }
        si.model = model("car_" + vc + ".obj");
        color_key = "color";
        break;
      }
      case EntityClass::kPedestrian:
        si.model = model("pedestrian.obj");
        color_key = "clothing_color";
        break;
      case EntityClass::kAircraft: {
        const std::string m = e.attributes.str("model");
        if (m != "fixed_wing" && m != "quadrotor") {
          throw RenderError(attributeError(e, "model", "fixed_wing or quadrotor"));
        }
        si.model = model("aircraft_" + m + ".obj");
        // Airplanes white, multirotors black.
        paintColor(m == "fixed_wing" ? "white" : "black", &si.record.color);
        break;
      }
    }
    if (!color_key.empty() && !paintColor(e.attributes.str(color_key), &si.record.color)) {
      throw RenderError(attributeError(e, color_key,
                                       "a colour name (red, blue, white, black, silver, grey, "
                                       "green, yellow, beige, brick, brown, orange)"));
    }
    boxRecordRows(e.box, lift, si.record.row);
    si.record.label = label(si.semantic, instance_id);
    const Mesh& mesh = models_[static_cast<std::size_t>(si.model)];
    si.radius = scaledRadius(mesh, e.box.size);
    const auto& levels = lods_[static_cast<std::size_t>(si.model)];
    si.lod_levels = static_cast<int>(levels.size());
    for (std::size_t l = 0; l < levels.size(); ++l) {
      si.lod_deviation[l] = levels[l].axis_error.cwiseProduct(e.box.size.cast<float>()).maxCoeff();
    }
    si.center = recordCenter(si.record, mesh);
    entity_ids_[static_cast<std::size_t>(instance_id)] = e.id;
    instances_.push_back(si);
  };
  for (std::size_t i = 0; i < n_world; ++i) {
    add(world.entities()[i], static_cast<int>(1 + i), -1, false);
  }
  for (std::size_t j = 0; j < config.entities.size(); ++j) {
    const auto& se = config.entities[j];
    add(se.entity, static_cast<int>(1 + n_world + j), static_cast<int>(j), !se.trajectory.empty());
  }
  const std::size_t n_config = config.entities.size();
  for (std::size_t k = 0; k < aircraft_.size(); ++k) {
    add(aircraft_[k].entity, static_cast<int>(1 + n_world + n_config + k),
        static_cast<int>(n_config + k), true);
  }
  // The city buildings' rooftop equipment: parts of their building (its label).
  for (std::size_t i = 0; i < n_world; ++i) {
    const scenario::Entity& e = world.entities()[i];
    if (e.cls != EntityClass::kBuilding) continue;
    for (const RooftopPart& part : rooftopEquipment(e)) {
      SceneInstance si;
      // The unit in light grey metal, the tank in weathered wood, the bulkhead in the
      // building's own colour.
      if (part.kind == RooftopPart::Kind::kUnit) {
        si.model = cityBox("rooftop_unit", MaterialKind::kPlain, srgbToLinear(168, 170, 172));
      } else if (part.kind == RooftopPart::Kind::kTank) {
        si.model = cityBox("water_tank", MaterialKind::kPlain, srgbToLinear(120, 92, 66));
      } else {
        si.model = cityBox("roof_bulkhead", MaterialKind::kPaint, Eigen::Vector3f(0.5f, 0.5f, 0.5f));
        if (!paintColor(e.attributes.str("color"), &si.record.color)) {
          throw RenderError(attributeError(e, "color", "a colour name"));
        }
      }
      si.part_of = static_cast<int>(1 + i);
      si.semantic = scenario::semanticId(e.cls);
      si.cls = e.cls;
      si.convex = true;
      si.box = part.box;
      boxRecordRows(part.box, 0.0, si.record.row);
      si.record.label = label(si.semantic, si.part_of);
      const Mesh& mesh = models_[static_cast<std::size_t>(si.model)];
      si.radius = scaledRadius(mesh, part.box.size);
      si.center = recordCenter(si.record, mesh);
      instances_.push_back(si);
    }
  }
}

const scenario::ScenarioEntity& Scene::scenarioEntity(int j) const {
  const auto k = static_cast<std::size_t>(j);
  return k < config_.entities.size() ? config_.entities[k] : aircraft_[k - config_.entities.size()];
}

void Scene::pose(std::size_t i, double time, InstanceRecord* record, Eigen::Vector3f* center,
                 float* radius) const {
  const SceneInstance& si = instances_[i];
  *record = si.record;
  *center = si.center;
  *radius = si.radius;
  if (!si.mover) return;
  const auto& se = scenarioEntity(si.scenario_entity);
  const geometry::OrientedBox box =
      scenario::poseBox(se.entity.box, scenario::sampleTrajectory(se.trajectory, time));
  boxRecordRows(box, 0.0, record->row);
  *center = recordCenter(*record, models_[static_cast<std::size_t>(si.model)]);
}

InstanceRecord Scene::uavRecord(const Eigen::Isometry3d& world_T_uav) const {
  InstanceRecord r;
  isometryRows(world_T_uav, r.row);
  r.label = label(kUavSemantic, uav_instance_);
  r.color = packRgb8(60, 60, 64);
  return r;
}

SceneTriangles Scene::triangles(double time, const LodView* lod) const {
  SceneTriangles out;
  for (std::size_t i = 0; i < instances_.size(); ++i) {
    InstanceRecord rec;
    Eigen::Vector3f center;
    float radius;
    pose(i, time, &rec, &center, &radius);
    const SceneInstance& si = instances_[i];
    const int model = lod ? modelFor(i, center, radius, *lod) : si.model;
    const Mesh& mesh = models_[static_cast<std::size_t>(model)];
    for (const Submesh& s : mesh.submeshes) {
      const bool canopy = s.kind == MaterialKind::kFoliage;
      if (canopy && foliage_ <= 0) continue;
      for (std::uint32_t k = s.first_index; k < s.first_index + s.index_count; ++k) {
        Eigen::Vector3f p = mesh.position(mesh.indices[k]);
        if (canopy) p = mesh.canopy_center + rec.canopy * (p - mesh.canopy_center);
        Eigen::Vector3f w;
        for (int r = 0; r < 3; ++r) {
          w[r] =
              rec.row[r][0] * p.x() + rec.row[r][1] * p.y() + rec.row[r][2] * p.z() + rec.row[r][3];
        }
        out.indices.push_back(static_cast<std::uint32_t>(out.vertices.size()));
        out.vertices.push_back(w);
      }
      out.triangle_instance.insert(out.triangle_instance.end(), s.index_count / 3,
                                   si.part_of > 0 ? si.part_of : si.instance_id);
    }
  }
  return out;
}

}  // namespace hameritt::render
