// The map of a city scenario draws the city classes: buildings darker the taller they are
// (surface car parks, the negative control, stay brighter than any building), and traffic
// lights as red dots.

#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <vector>

#include "hameritt/map/scenario_map.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/scenario_io.h"

namespace hameritt::map {
namespace {

using nlohmann::json;
using scenario::EntityClass;

struct CityMap {
  scenario::World world;
  cv::Mat img;
  MapFrame frame;
};

const CityMap& cityMap() {
  static const CityMap m = [] {
    scenario::WorldParams p =
        scenario::loadWorldParams(scenario::defaultConfigDir() + "/world.json");
    p.type = scenario::WorldType::kCity;
    CityMap c{scenario::generateWorld(p), {}, {}};
    const auto cfg =
        scenario::loadGeneratorConfig(scenario::defaultConfigDir() + "/generator.json");
    const scenario::Scenario s =
        scenario::generateScenario(c.world, cfg, scenario::ScenarioClass::kAreaSearch, 3);
    json mission = json::parse(scenario::missionJson(s.mission));
    json sim = json::parse(scenario::simConfigJson(s.sim));
    // Only the world: no overlays that would tint it, and none of the city's traffic and crowd
    // (their markers and paths cover the corners where the traffic lights stand).
    for (const char* k : {"areas_of_interest", "keep_out_zones", "area_priors", "routes"}) {
      mission[k] = json::array();
    }
    json kept = json::array();
    for (const auto& e : sim["entities"]) {
      if (e["role"] != "traffic" && e["role"] != "pedestrian") kept.push_back(e);
    }
    sim["entities"] = kept;
    MapStyle style;
    style.crop_to_interest = false;
    c.img = drawScenarioMap(c.world, mission, sim, style);
    c.frame = computeMapFrame(c.world, mission, sim, style);
    return c;
  }();
  return m;
}

// Median of v (v not empty).
int medianOf(std::vector<int> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

int brightness(const cv::Mat& img, const cv::Point& p) {
  const cv::Vec3b v = img.at<cv::Vec3b>(p);
  return v[0] + v[1] + v[2];
}

TEST(CityMap, BuildingsArePaintedDarkerWithHeight) {
  // Medians, as markers and labels of the scenario's entities cover a few centres.
  const CityMap& m = cityMap();
  std::vector<int> low, tall, lots;
  for (const auto& e : m.world.entities()) {
    const int b = brightness(m.img, m.frame.pixelAt(e.box.center2()));
    if (e.cls == EntityClass::kBuilding && e.box.size.z() <= 14.0) low.push_back(b);
    if (e.cls == EntityClass::kBuilding && e.box.size.z() >= 100.0) tall.push_back(b);
    // Surface car parks, the centre between the rows of stalls.
    if (e.cls == EntityClass::kParkingLot) lots.push_back(b);
  }
  ASSERT_GT(low.size(), 10u);
  ASSERT_GT(tall.size(), 5u);
  EXPECT_EQ(lots.size(), 27u);
  EXPECT_LT(medianOf(tall) + 60, medianOf(low));
  // Negative control: the same measure tells a pale surface from a building.
  EXPECT_GT(medianOf(lots), medianOf(low) + 30);
}

TEST(CityMap, LampPostsAndTrafficLightsCarryDots) {
  const CityMap& m = cityMap();
  int checked = 0;
  for (const auto& e : m.world.entities()) {
    if (e.cls != EntityClass::kTrafficLight) continue;
    const cv::Vec3b v = m.img.at<cv::Vec3b>(m.frame.pixelAt(e.box.center2()));
    // kKozEdge, RGB (165, 15, 25): red dominates (OpenCV stores BGR).
    EXPECT_GT(v[2], v[1] + 60) << e.id;
    if (++checked == 10) break;
  }
  EXPECT_EQ(checked, 10);
}

}  // namespace
}  // namespace hameritt::map
