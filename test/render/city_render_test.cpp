// The city's classes in the renderer: a straight-down view over a building labels its pixels
// with the building's class and instance and measures the depth to its roof; hiding the
// building (the negative control) shows the ground behind it instead. A low front view down a
// street labels the street furniture classes. The city's classes get 2D boxes and occlusion
// fractions: an entity drawn alone has the box of its projected geometry and no occlusion, and
// in a street view a partly hidden one has 0 < occlusion < 1, its total the pixels it covers
// drawn alone. A building's rooftop equipment is solid and part of it.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <set>

#include "hameritt/generation/generator.h"
#include "render_test_util.h"
#include "scene.h"

namespace hameritt::render {
namespace {

using scenario::EntityClass;
using testing::lookAt;

const scenario::World& cityWorld() {
  static const scenario::World w = [] {
    scenario::WorldParams p =
        scenario::loadWorldParams(std::string(HAMERITT_SOURCE_DIR) + "/config/world.json");
    p.type = scenario::WorldType::kCity;
    return scenario::generateWorld(p);
  }();
  return w;
}

// A city scenario's sim_config with the world's own parameters and no movers.
const scenario::SimConfig& citySimConfig() {
  static const scenario::SimConfig c = [] {
    scenario::SimConfig s = testing::defaultSimConfig();
    s.world = cityWorld().params();
    s.world_fingerprint = cityWorld().fingerprint();
    s.entities.clear();
    s.groups.clear();
    return s;
  }();
  return c;
}

Renderer& cityRenderer() {
  static Renderer r(cityWorld(), citySimConfig());
  return r;
}

RenderRequest request(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  RenderRequest r;
  r.intrinsics = intrinsicsFromHfov(320, 240, 60.0);
  r.world_T_optical = lookAt(eye, target);
  r.time = 0.0;
  r.noise = false;
  r.weather = false;
  return r;
}

const scenario::Entity& firstOf(EntityClass cls, double min_height) {
  for (const auto& e : cityWorld().entities()) {
    if (e.cls == cls && e.box.size.z() >= min_height) return e;
  }
  throw std::runtime_error("no entity of the class");
}

TEST(CityRender, DownViewLabelsABuildingAndMeasuresItsRoof) {
  const auto& b = firstOf(EntityClass::kBuilding, 20.0);
  const Eigen::Vector3d c(b.box.center.x(), b.box.center.y(), 0.0);
  const double h = b.box.size.z();
  // Straight down from 200 m (a hair off vertical so that lookAt has a level x axis).
  RenderRequest r = request(c + Eigen::Vector3d(0, 0, 200.0), c + Eigen::Vector3d(0, 1e-3, 0));
  const FrameSet f = cityRenderer().render(r);
  const std::size_t mid = static_cast<std::size_t>(120 * 320 + 160);
  EXPECT_EQ(f.semantic[mid], scenario::semanticId(EntityClass::kBuilding));
  EXPECT_EQ(cityRenderer().instanceEntityId(f.instance[mid]), b.id);
  EXPECT_NEAR(f.depth[mid], 200.0 - h, 0.05);
  // Negative control: with the building hidden the same pixel sees the ground (or whatever
  // stands lower behind it), not this roof.
  r.hidden_entities = {b.id};
  const FrameSet g = cityRenderer().render(r);
  EXPECT_NE(cityRenderer().instanceEntityId(g.instance[mid]), b.id);
  EXPECT_GT(g.depth[mid], 200.0 - h + 1.0);
}

// The rooftop equipment is solid: seen straight down, the pixels over a building's unit and tank
// are nearer than its roof by their heights and carry the building's class and instance (they
// are parts of it); hiding the building hides them too (the negative control: the same pixels
// then see something lower than the roof); the ray-cast triangles of the building reach the
// tank's top.
TEST(CityRender, RooftopEquipmentIsSolidAndPartOfItsBuilding) {
  const auto& w = cityWorld();
  std::size_t index = 0;
  std::vector<RooftopPart> parts;
  for (; index < w.entities().size(); ++index) {
    const auto& e = w.entities()[index];
    if (e.cls != EntityClass::kBuilding || e.box.size.z() < 20.0) continue;
    parts = rooftopEquipment(e);
    if (parts.size() >= 2) break;
  }
  ASSERT_LT(index, w.entities().size()) << "no building with a unit and a tank";
  const auto& b = w.entities()[index];
  const double roof = b.box.maxZ();
  int buildings_with_parts = 0;
  for (const auto& e : w.entities()) {
    if (e.cls == EntityClass::kBuilding && !rooftopEquipment(e).empty()) ++buildings_with_parts;
  }
  EXPECT_GT(buildings_with_parts, 100);
  const Eigen::Vector3d c(b.box.center.x(), b.box.center.y(), 0.0);
  const double eye = roof + 60.0;
  RenderRequest r = request(c + Eigen::Vector3d(0, 0, eye), c + Eigen::Vector3d(0, 1e-3, 0));
  const FrameSet f = cityRenderer().render(r);
  std::vector<std::size_t> on_parts;
  std::array<int, 2> tops{0, 0};  // pixels at the unit's top and at the tank's top
  for (std::size_t i = 0; i < f.depth.size(); ++i) {
    if (cityRenderer().instanceEntityId(f.instance[i]) != b.id) continue;
    ASSERT_EQ(f.semantic[i], scenario::semanticId(EntityClass::kBuilding));
    for (std::size_t k = 0; k < 2; ++k) {
      if (std::abs(f.depth[i] - (eye - parts[k].box.maxZ())) < 0.05) ++tops[k];
    }
    if (f.depth[i] < eye - roof - 0.5) on_parts.push_back(i);
  }
  EXPECT_GT(tops[0], 50) << "the unit's top";
  EXPECT_GT(tops[1], 50) << "the tank's top";
  EXPECT_EQ(parts[0].kind, RooftopPart::Kind::kUnit);
  EXPECT_EQ(parts[1].kind, RooftopPart::Kind::kTank);
  EXPECT_NEAR(parts[0].box.maxZ() - roof, 1.3, 1e-9);
  EXPECT_NEAR(parts[1].box.maxZ() - roof, 3.2, 1e-9);
  r.hidden_entities = {b.id};
  const FrameSet g = cityRenderer().render(r);
  ASSERT_FALSE(on_parts.empty());
  for (std::size_t i : on_parts) {
    ASSERT_NE(cityRenderer().instanceEntityId(g.instance[i]), b.id);
    ASSERT_GT(g.depth[i], eye - roof + 0.5) << "pixel " << i << " still sees a part";
  }
  const SceneTriangles t = cityRenderer().sceneTriangles(0.0);
  float top = 0.0f;
  for (std::size_t k = 0; k < t.triangle_instance.size(); ++k) {
    if (t.triangle_instance[k] != static_cast<int>(1 + index)) continue;
    for (int j = 0; j < 3; ++j) top = std::max(top, t.vertices[t.indices[3 * k + j]].z());
  }
  EXPECT_NEAR(top, parts[1].box.maxZ(), 1e-3);
  std::printf("%s: roof %.2f m, %zu parts; %d and %d pixels on the unit's and the tank's tops; "
              "%d buildings of the city have rooftop equipment\n",
              b.id.c_str(), roof, parts.size(), tops[0], tops[1], buildings_with_parts);
}

TEST(CityRender, StreetViewLabelsTheCityClasses) {
  // Along a street from 8 m up, looking down the street a little: buildings, street trees,
  // lamp posts, and (on the way) traffic lights or bus stops.
  const auto& w = cityWorld();
  std::set<int> seen;
  int views = 0;
  for (const auto& e : w.edges()) {
    if (views >= 6) break;
    const auto a = w.nodes()[static_cast<std::size_t>(e.a)].position;
    const auto bpos = w.nodes()[static_cast<std::size_t>(e.b)].position;
    const Eigen::Vector3d eye(a.x(), a.y(), 8.0);
    const Eigen::Vector3d at(bpos.x(), bpos.y(), 3.0);
    const FrameSet f = cityRenderer().render(request(eye, at));
    ++views;
    for (std::size_t i = 0; i < f.semantic.size(); ++i) {
      seen.insert(f.semantic[i]);
      // Every labelled pixel's instance belongs to an entity of the same class.
      const std::string& id = cityRenderer().instanceEntityId(f.instance[i]);
      if (id.empty()) continue;
      const int k = w.find(id);
      ASSERT_GE(k, 0) << id;
      ASSERT_EQ(scenario::semanticId(w.entities()[static_cast<std::size_t>(k)].cls), f.semantic[i])
          << id;
    }
  }
  EXPECT_EQ(views, 6);
  for (EntityClass cls : {EntityClass::kBuilding, EntityClass::kStreetTree, EntityClass::kLampPost,
                          EntityClass::kStreet}) {
    EXPECT_TRUE(seen.count(scenario::semanticId(cls))) << scenario::toString(cls);
  }
}

// Every world entity but `keep`: hidden, nothing can stand in front of it (the ground layers lie
// below every object).
std::vector<std::string> allBut(const std::string& keep) {
  std::vector<std::string> out;
  for (const auto& e : cityWorld().entities()) {
    if (e.id != keep) out.push_back(e.id);
  }
  return out;
}

const BoundingBox* boxOf(const FrameSet& f, const std::string& id) {
  for (const auto& b : f.boxes) {
    if (b.entity_id == id) return &b;
  }
  return nullptr;
}

// The pixel-centre extent [x0, x1] x [y0, y1] of a box's projection: the pixels whose centres
// lie within the projected corners' range (every corner in front of the camera).
std::array<double, 4> projectedExtent(const RenderRequest& r, const geometry::OrientedBox& box,
                                      const Eigen::Vector3d& shift) {
  const double c = std::cos(box.yaw), s = std::sin(box.yaw);
  std::array<double, 4> e{1e300, 1e300, -1e300, -1e300};
  for (int k = 0; k < 8; ++k) {
    const double lx = ((k & 1) ? 0.5 : -0.5) * box.size.x();
    const double ly = ((k & 2) ? 0.5 : -0.5) * box.size.y();
    const Eigen::Vector3d p(box.center.x() + c * lx - s * ly, box.center.y() + s * lx + c * ly,
                            (k & 4) ? box.maxZ() : box.minZ());
    Eigen::Vector2d uv;
    EXPECT_TRUE(projectPoint(r.intrinsics, r.world_T_optical, p + shift, &uv));
    e[0] = std::min(e[0], uv.x());
    e[1] = std::min(e[1], uv.y());
    e[2] = std::max(e[2], uv.x());
    e[3] = std::max(e[3], uv.y());
  }
  return e;
}

// The largest distance (pixels) between a box's pixel bounds and a projected extent.
double boxError(const BoundingBox& b, const std::array<double, 4>& e) {
  return std::max({std::abs(b.x_min - e[0]), std::abs(b.y_min - e[1]), std::abs(b.x_max - e[2]),
                   std::abs(b.y_max - e[3])});
}

TEST(CityRender, CityClassesAloneHaveTheBoxOfTheirProjectedGeometry) {
  int checked = 0;
  for (EntityClass cls :
       {EntityClass::kBuilding, EntityClass::kLampPost, EntityClass::kBusStop,
        EntityClass::kTrafficLight, EntityClass::kBench, EntityClass::kParkingGarage}) {
    const auto& e = firstOf(cls, cls == EntityClass::kBuilding ? 20.0 : 0.0);
    const double size = e.box.size.maxCoeff();
    // From the side and a little above, far enough that the whole entity is in view.
    const Eigen::Vector3d c(e.box.center.x(), e.box.center.y(),
                            0.5 * (e.box.minZ() + e.box.maxZ()));
    const Eigen::Vector3d eye = c + Eigen::Vector3d(0.8, 0.6, 0.35) * (2.0 * size + 2.0);
    RenderRequest r = request(eye, c);
    r.hidden_entities = allBut(e.id);
    const FrameSet f = cityRenderer().render(r);
    const BoundingBox* b = boxOf(f, e.id);
    ASSERT_NE(b, nullptr) << e.id;
    EXPECT_EQ(b->cls, cls) << e.id;
    EXPECT_EQ(b->role, "world");
    EXPECT_EQ(b->visible_pixels, std::count(f.instance.begin(), f.instance.end(), b->instance));
    EXPECT_GT(b->visible_pixels, 100) << e.id;
    // Alone: nothing in front of it but the sidewalk slab (1 cm above the lawn) over the foot of
    // its walls, at most a row of pixels.
    EXPECT_GE(b->total_pixels, b->visible_pixels) << e.id;
    EXPECT_LE(b->total_pixels - b->visible_pixels, b->x_max - b->x_min + 1) << e.id;
    EXPECT_LT(b->occlusion, 0.01) << e.id;
    const auto extent = projectedExtent(r, e.box, Eigen::Vector3d::Zero());
    EXPECT_GE(std::min(extent[0], extent[1]), 0.0) << e.id;
    EXPECT_LE(extent[2], r.intrinsics.width - 1.0) << e.id;
    EXPECT_LE(extent[3], r.intrinsics.height - 1.0) << e.id;
    EXPECT_LE(boxError(*b, extent), 1.5) << e.id;
    // Negative control: the geometry moved by 5 % of its size to the camera's right is not this
    // box.
    const Eigen::Vector3d right = 0.05 * size * r.world_T_optical.linear().col(0);
    EXPECT_GT(boxError(*b, projectedExtent(r, e.box, right)), 3.0) << e.id;
    ++checked;
  }
  EXPECT_EQ(checked, 6);
}

TEST(CityRender, PartlyHiddenCityEntitiesHaveAFractionOfTheirPixelsVisible) {
  // Street views as above; the first partly hidden building, lamp post and street tree (the
  // tree's mesh is not convex: its total comes from the grouped redraw, the boxes' from a query).
  const auto& w = cityWorld();
  std::map<EntityClass, int> found;
  int views = 0;
  for (const auto& edge : w.edges()) {
    if (found.size() == 3 || views >= 120) break;
    const auto a = w.nodes()[static_cast<std::size_t>(edge.a)].position;
    const auto bpos = w.nodes()[static_cast<std::size_t>(edge.b)].position;
    const RenderRequest r =
        request(Eigen::Vector3d(a.x(), a.y(), 8.0), Eigen::Vector3d(bpos.x(), bpos.y(), 3.0));
    const FrameSet f = cityRenderer().render(r);
    ++views;
    for (const auto& b : f.boxes) {
      ASSERT_EQ(b.visible_pixels, std::count(f.instance.begin(), f.instance.end(), b.instance));
      ASSERT_GE(b.total_pixels, b.visible_pixels);
      ASSERT_EQ(b.occlusion, 1.0 - static_cast<double>(b.visible_pixels) / b.total_pixels);
      if (b.cls != EntityClass::kBuilding && b.cls != EntityClass::kLampPost &&
          b.cls != EntityClass::kStreetTree) {
        continue;
      }
      if (found.count(b.cls) || b.visible_pixels < 20 || b.occlusion < 0.05 || b.occlusion > 0.95) {
        continue;
      }
      // Its total is what it covers drawn alone; drawn alone it is not hidden at all (the
      // negative control: the same entity, the occluders gone, has no occlusion).
      RenderRequest alone = r;
      alone.hidden_entities = allBut(b.entity_id);
      const FrameSet g = cityRenderer().render(alone);
      const BoundingBox* ba = boxOf(g, b.entity_id);
      ASSERT_NE(ba, nullptr);
      // (less the foot of its walls under the sidewalk slab: at most a row of pixels).
      const int alone_pixels =
          static_cast<int>(std::count(g.instance.begin(), g.instance.end(), b.instance));
      EXPECT_GE(b.total_pixels, alone_pixels) << b.entity_id;
      EXPECT_LE(b.total_pixels - alone_pixels, ba->x_max - ba->x_min + 1) << b.entity_id;
      EXPECT_GT(b.occlusion, 0.0);
      EXPECT_LT(b.occlusion, 1.0);
      EXPECT_LT(ba->occlusion, 0.01) << b.entity_id;
      EXPECT_EQ(ba->total_pixels, b.total_pixels) << b.entity_id;
      // The visible box lies within the unoccluded one.
      EXPECT_GE(b.x_min, ba->x_min);
      EXPECT_LE(b.x_max, ba->x_max);
      EXPECT_GE(b.y_min, ba->y_min);
      EXPECT_LE(b.y_max, ba->y_max);
      found[b.cls] = 1;
    }
  }
  EXPECT_EQ(found.size(), 3u) << "in " << views << " views";
}

// Calls visit(pixel index, world height) for every pixel of an instance.
template <typename Visit>
void forEachPixelHeight(const FrameSet& f, const RenderRequest& r, int instance, Visit visit) {
  const Intrinsics& k = r.intrinsics;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v * k.width + u);
      if (f.instance[i] != instance) continue;
      const Eigen::Vector3d ray((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      visit(i, (r.world_T_optical * (f.depth[i] * ray)).z());
    }
  }
}

// Mean luminance of an entity's wall pixels binned by the phase of their world height in a
// period, as (max - min) / mean over 12 bins: high when the colour repeats with that period.
double bandContrast(const FrameSet& f, const RenderRequest& r, int instance, double period) {
  std::array<double, 12> sum{}, n{};
  forEachPixelHeight(f, r, instance, [&](std::size_t i, double z) {
    const double phase = z / period - std::floor(z / period);
    const auto b = std::min<std::size_t>(11, static_cast<std::size_t>(phase * 12));
    sum[b] += 0.2126 * f.rgb[3 * i] + 0.7152 * f.rgb[3 * i + 1] + 0.0722 * f.rgb[3 * i + 2];
    n[b] += 1;
  });
  double lo = 1e300, hi = -1e300, all = 0, count = 0;
  for (std::size_t b = 0; b < 12; ++b) {
    if (n[b] < 20) return 0.0;
    lo = std::min(lo, sum[b] / n[b]);
    hi = std::max(hi, sum[b] / n[b]);
    all += sum[b];
    count += n[b];
  }
  return (hi - lo) / (all / count);
}

// A camera square to an entity's +x face at mid-height, the face filling most of the view,
// everything else hidden.
RenderRequest faceView(const scenario::Entity& e) {
  const Eigen::Vector3d n(std::cos(e.box.yaw), std::sin(e.box.yaw), 0.0);
  const Eigen::Vector3d face = e.box.center + 0.5 * e.box.size.x() * n;
  const double dist = 1.3 * std::max(e.box.size.y(), e.box.size.z()) + 5.0;
  RenderRequest r = request(face + dist * n, face);
  r.hidden_entities = allBut(e.id);
  return r;
}

TEST(CityRender, FacadesHaveWindowBandsWithTheStoreyPeriod) {
  const scenario::Entity* b = nullptr;
  for (const auto& e : cityWorld().entities()) {
    if (e.cls == EntityClass::kBuilding && e.attributes.integer("storeys", 0) >= 6 &&
        e.box.size.z() < 60.0) {
      b = &e;
      break;
    }
  }
  ASSERT_NE(b, nullptr);
  const double storey = b->box.size.z() / static_cast<double>(b->attributes.integer("storeys", 1));
  const RenderRequest r = faceView(*b);
  const FrameSet f = cityRenderer().render(r);
  const int id = cityRenderer().instanceOf(b->id);
  const double at_storey = bandContrast(f, r, id, storey);
  const double off_storey = bandContrast(f, r, id, 0.77 * storey);
  std::printf("%s: band contrast %.3f at the storey height, %.3f at 0.77 of it\n", b->id.c_str(),
              at_storey, off_storey);
  EXPECT_GT(at_storey, 0.2) << b->id;
  EXPECT_GT(at_storey, 4.0 * off_storey) << b->id;
  // Deterministic: the same request gives the same colours.
  EXPECT_EQ(f.rgb, cityRenderer().render(r).rgb);
  // Negative control: a parking garage is a plain box; its colour does not repeat with its
  // storey height.
  const auto& g = firstOf(EntityClass::kParkingGarage, 0.0);
  const RenderRequest rg = faceView(g);
  const FrameSet fg = cityRenderer().render(rg);
  const double garage = bandContrast(fg, rg, cityRenderer().instanceOf(g.id), 3.0);
  std::printf("%s: band contrast %.3f\n", g.id.c_str(), garage);
  EXPECT_LT(garage, 0.05) << g.id;
}

// Mean colour of an entity's pixels whose world height lies in [z0, z1).
Eigen::Vector3d meanColour(const FrameSet& f, const RenderRequest& r, int instance, double z0,
                           double z1) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  forEachPixelHeight(f, r, instance, [&](std::size_t i, double z) {
    if (z < z0 || z >= z1) return;
    sum += Eigen::Vector3d(f.rgb[3 * i], f.rgb[3 * i + 1], f.rgb[3 * i + 2]);
    ++n;
  });
  EXPECT_GT(n, 30);
  return sum / std::max(n, 1);
}

// A close-up of the first traffic-light mast's head, looking along axis 0 at its +x face, with
// one signalised intersection beside the mast whose axis 0 runs along the mast's x axis.
struct MastCloseUp {
  const scenario::Entity& mast = firstOf(EntityClass::kTrafficLight, 0.0);
  scenario::SignalizedIntersection is;
  scenario::SignalPlan plan;
  std::unique_ptr<Renderer> renderer;
  RenderRequest r;
  int id = -1;
  double top = 0.0;

  MastCloseUp() {
    scenario::SimConfig cfg = citySimConfig();
    is.id = "signal_00";
    is.position = mast.box.center2() + geometry::Vec2(5.0, 5.0);
    is.heading[0] = mast.box.yaw;
    is.heading[1] = mast.box.yaw + 0.5 * M_PI;
    is.width[0] = is.width[1] = 20.0;
    plan.intersections = {is};
    cfg.signals = plan;
    renderer = std::make_unique<Renderer>(cityWorld(), cfg);
    const Eigen::Vector3d x(std::cos(mast.box.yaw), std::sin(mast.box.yaw), 0.0);
    const Eigen::Vector3d head(mast.box.center.x(), mast.box.center.y(), mast.box.maxZ() - 0.6);
    r = request(head + 3.0 * x, head);
    r.hidden_entities = allBut(mast.id);
    id = renderer->instanceOf(mast.id);
    top = mast.box.maxZ();
  }
  // The first time (on a 0.5 s grid) at which `axis` shows `state`, or -1.
  double firstTime(scenario::SignalState state, int axis = 0) const {
    for (double t = 0.25; t < plan.cycle(); t += 0.5) {
      if (plan.state(is, axis, t) == state) return t;
    }
    return -1.0;
  }
  FrameSet frameAt(double t) {
    r.time = t;
    return renderer->render(r);
  }
};

TEST(CityRender, TrafficLightLampsFollowTheSignalPlan) {
  MastCloseUp m;
  // Times when axis 0 shows red, then green.
  const double t_red = m.firstTime(scenario::SignalState::kRed);
  const double t_green = m.firstTime(scenario::SignalState::kGreen);
  ASSERT_GE(t_red, 0.0);
  ASSERT_GE(t_green, 0.0);
  const RenderRequest& r = m.r;
  const int id = m.id;
  const double top = m.top;
  auto lamps = [&](double t) {
    const FrameSet f = m.frameAt(t);
    // Red lamp (top 0.4 m) and green lamp (0.8-1.2 m below the top), away from the band edges.
    return std::make_pair(meanColour(f, r, id, top - 0.35, top - 0.05),
                          meanColour(f, r, id, top - 1.15, top - 0.85));
  };
  const auto [red_at_red, green_at_red] = lamps(t_red);
  const auto [red_at_green, green_at_green] = lamps(t_green);
  std::printf("red lamp R %.0f at red, %.0f at green; green lamp G %.0f at red, %.0f at green\n",
              red_at_red.x(), red_at_green.x(), green_at_red.y(), green_at_green.y());
  EXPECT_GT(red_at_red.x(), 3.0 * red_at_green.x());
  EXPECT_GT(green_at_green.y(), 3.0 * green_at_red.y());
  EXPECT_GT(red_at_red.x(), 2.0 * red_at_red.y());          // red, not white
  EXPECT_GT(green_at_green.y(), 2.0 * green_at_green.x());  // green
  // Negative control: without a signal plan every lamp is dark at both times.
  m.r.time = t_red;
  const FrameSet f = cityRenderer().render(m.r);
  EXPECT_LT(meanColour(f, r, id, top - 0.35, top - 0.05).x(), 0.5 * red_at_red.x());
}

// Share of an entity's pixels whose world height lies in [z0, z1), on the image's left (side <
// 0) or right (side > 0) of the entity's mean column, that are lit green (G above 160 and
// half as much again as R).
double greenShare(const FrameSet& f, const RenderRequest& r, int instance, double z0, double z1,
                  int side) {
  const int w = r.intrinsics.width;
  double cols = 0, n_all = 0;
  forEachPixelHeight(f, r, instance, [&](std::size_t i, double) {
    cols += static_cast<double>(i % static_cast<std::size_t>(w));
    n_all += 1;
  });
  const double mid = cols / std::max(1.0, n_all);
  int n = 0, lit = 0;
  forEachPixelHeight(f, r, instance, [&](std::size_t i, double z) {
    const double col = static_cast<double>(i % static_cast<std::size_t>(w));
    if (z < z0 || z >= z1 || (side < 0 ? col >= mid : col < mid)) return;
    ++n;
    lit += f.rgb[3 * i + 1] > 160 && f.rgb[3 * i + 1] > 1.5 * f.rgb[3 * i];
  });
  EXPECT_GT(n, 15);
  return static_cast<double>(lit) / std::max(n, 1);
}

TEST(CityRender, ProtectedLeftArrowShowsAGreenArrowBesideTheRedLamp) {
  MastCloseUp m;
  const double t_arrow = m.firstTime(scenario::SignalState::kLeftArrow);
  const double t_red = m.firstTime(scenario::SignalState::kRed);
  const double t_green = m.firstTime(scenario::SignalState::kGreen);
  ASSERT_GE(t_arrow, 0.0);
  ASSERT_GE(t_red, 0.0);
  ASSERT_GE(t_green, 0.0);
  struct Lamps {
    double red = 0, left = 0, right = 0;  // red lamp's R; green share of the green lamp's halves
  };
  auto lamps = [&](double t) {
    const FrameSet f = m.frameAt(t);
    return Lamps{meanColour(f, m.r, m.id, m.top - 0.35, m.top - 0.05).x(),
                 greenShare(f, m.r, m.id, m.top - 1.15, m.top - 0.85, -1),
                 greenShare(f, m.r, m.id, m.top - 1.15, m.top - 0.85, 1)};
  };
  const Lamps arrow = lamps(t_arrow), red = lamps(t_red), green = lamps(t_green);
  std::printf(
      "red lamp R: arrow %.0f, red %.0f, green %.0f; green share of the green lamp's left and "
      "right halves: arrow %.2f %.2f, red %.2f %.2f, green %.2f %.2f\n",
      arrow.red, red.red, green.red, arrow.left, arrow.right, red.left, red.right, green.left,
      green.right);
  // On the arrow the red lamp is lit, as on red, and not on green.
  EXPECT_GT(arrow.red, 3.0 * green.red);
  // The green lamp's place shows some green on the arrow, none on red (the negative control).
  EXPECT_GT(arrow.left, 0.15);
  EXPECT_LT(red.left + red.right, 0.02);
  // An arrow pointing left, not the round lamp (the negative control, lit all over): its head
  // makes more of the left half green than of the right.
  EXPECT_GT(green.left, 0.9);
  EXPECT_GT(green.right, 0.9);
  EXPECT_LT(arrow.left, 0.6);
  EXPECT_GT(arrow.left, 1.3 * arrow.right);
  EXPECT_LT(green.left, 1.3 * green.right);  // the same criterion fails the round lamp
  EXPECT_GT(arrow.right, 0.05);              // the shaft
}

TEST(CityRender, CrossStreetArrowShowsAGreenRightArrowBesideTheRedLamp) {
  MastCloseUp m;
  // While axis 1 shows its protected left arrow, axis 0 is red and its right turns go.
  const double t_cross = m.firstTime(scenario::SignalState::kLeftArrow, 1);
  const double t_left = m.firstTime(scenario::SignalState::kLeftArrow);
  const double t_red = m.firstTime(scenario::SignalState::kRed);
  ASSERT_GE(t_cross, 0.0);
  ASSERT_GE(t_left, 0.0);
  ASSERT_GE(t_red, 0.0);
  ASSERT_EQ(m.plan.state(m.is, 0, t_cross), scenario::SignalState::kRed);
  auto lamps = [&](double t) {
    const FrameSet f = m.frameAt(t);
    return std::array<double, 3>{meanColour(f, m.r, m.id, m.top - 0.35, m.top - 0.05).x(),
                                 greenShare(f, m.r, m.id, m.top - 1.15, m.top - 0.85, -1),
                                 greenShare(f, m.r, m.id, m.top - 1.15, m.top - 0.85, 1)};
  };
  // A red time while neither axis shows an arrow: the negative control (no arrow).
  double t_plain = -1.0;
  for (double t = 0.25; t < m.plan.cycle() && t_plain < 0; t += 0.5) {
    if (m.plan.state(m.is, 0, t) == scenario::SignalState::kRed &&
        m.plan.state(m.is, 1, t) != scenario::SignalState::kLeftArrow)
      t_plain = t;
  }
  ASSERT_GE(t_plain, 0.0);
  const auto cross = lamps(t_cross), left = lamps(t_left), plain = lamps(t_plain);
  std::printf(
      "red lamp R: cross arrow %.0f, plain red %.0f; green share of the green lamp's left and "
      "right halves: cross arrow %.2f %.2f, own left arrow %.2f %.2f, plain red %.2f %.2f\n",
      cross[0], plain[0], cross[1], cross[2], left[1], left[2], plain[1], plain[2]);
  // The red lamp is lit, as on plain red.
  EXPECT_GT(cross[0], 0.5 * plain[0]);
  // Green light in the green lamp's place, none on plain red (the negative control).
  EXPECT_GT(cross[2], 0.15);
  EXPECT_LT(plain[1] + plain[2], 0.02);
  // An arrow pointing right: its head makes more of the right half green than of the left; the
  // own left arrow (the negative control) the other way round.
  EXPECT_LT(cross[2], 0.6);
  EXPECT_GT(cross[2], 1.3 * cross[1]);
  EXPECT_GT(cross[1], 0.05);  // the shaft
  EXPECT_GT(left[1], 1.3 * left[2]);
}

}  // namespace
}  // namespace hameritt::render
