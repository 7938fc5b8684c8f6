// The city's classes in the renderer: a straight-down view over a building labels its pixels
// with the building's class and instance and measures the depth to its roof; hiding the
// building (the negative control) shows the ground behind it instead. A low front view down a
// street labels the street furniture classes.

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "hameritt/generation/generator.h"
#include "render_test_util.h"

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

}  // namespace
}  // namespace hameritt::render
