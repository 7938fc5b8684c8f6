// The map of an avoid scenario: the goal's ring at its radius and every aircraft's t = 0
// marker, all inside the cropped frame; without the avoid phase there is no ring (the control).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "hameritt/generation/generator.h"
#include "hameritt/map/scenario_map.h"
#include "hameritt/scenario/params_table.h"
#include "hameritt/scenario/scenario_io.h"

namespace hameritt::map {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

cv::Vec3b bgr(const cv::Scalar& c) {
  return {static_cast<uchar>(c[0]), static_cast<uchar>(c[1]), static_cast<uchar>(c[2])};
}

// Pixels of colour `want` on the ring of radius r around c (sampled every 10 degrees).
int ringHits(const cv::Mat& img, const cv::Point2d& c, double r, const cv::Vec3b& want) {
  int hits = 0;
  for (int k = 0; k < 36; ++k) {
    const double a = k * M_PI / 18.0;
    const cv::Point p(static_cast<int>(std::lround(c.x + r * std::cos(a))),
                      static_cast<int>(std::lround(c.y - r * std::sin(a))));
    if (cv::Rect(0, 0, img.cols, img.rows).contains(p) && img.at<cv::Vec3b>(p) == want) ++hits;
  }
  return hits;
}

TEST(AvoidMap, GoalRingAndAircraftMarkers) {
  const std::string config = scenario::defaultConfigDir();
  const scenario::World world =
      scenario::generateWorld(scenario::loadWorldParams(config + "/world.json"));
  const auto gen = scenario::loadGeneratorConfig(config + "/generator.json");
  const scenario::Scenario s =
      scenario::generateScenario(world, gen, scenario::ScenarioClass::kAvoid, 2);
  const std::string root =
      (fs::temp_directory_path() / ("hameritt_avoid_map_" + std::to_string(::getpid()))).string();
  fs::remove_all(root);
  fs::create_directories(root);
  const std::string dir = scenario::writeScenarioDir(root, s);
  MapStyle style;
  style.px_per_m = 2.0;            // a 5 m goal radius is a 10 px ring
  style.crop_to_interest = false;  // the same frame with and without the goal
  const json mission = scenario::readJsonFile(dir + "/mission.json");
  const json sim = scenario::readJsonFile(dir + "/sim_config.json");
  const MapFrame f = computeMapFrame(world, mission, sim, style);
  writeScenarioMap(dir, root + "/map.png", style);
  const cv::Mat img = cv::imread(root + "/map.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());

  const auto& goal = mission["phases"][0]["goal"];
  const cv::Point2d g = f.toPixel({goal[0].get<double>(), goal[1].get<double>()});
  ASSERT_TRUE(f.map_rect.contains(cv::Point(static_cast<int>(g.x), static_cast<int>(g.y))));
  const double r = mission["phases"][0]["goal_radius"].get<double>() * style.px_per_m;
  EXPECT_GE(ringHits(img, g, r, bgr(kGoalColor)), 18);
  int markers = 0;
  for (const auto& a : sim["aircraft"]) {
    const auto& p0 = a["trajectory"][0];
    const cv::Point p = f.pixelAt({p0[1].get<double>(), p0[2].get<double>()});
    ASSERT_TRUE(f.map_rect.contains(p)) << a["id"];
    markers += img.at<cv::Vec3b>(p) == bgr(kAircraftColor) ? 1 : 0;
  }
  EXPECT_EQ(markers, static_cast<int>(sim["aircraft"].size()));
  EXPECT_GE(markers, 2);

  // Control: the same scenario without its avoid phase has no ring there.
  json bare = mission;
  bare.erase("phases");
  {
    std::ofstream out(dir + "/mission.json");
    out << bare.dump();
  }
  writeScenarioMap(dir, root + "/bare.png", style);
  const cv::Mat plain = cv::imread(root + "/bare.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(plain.empty());
  EXPECT_LE(ringHits(plain, g, r, bgr(kGoalColor)), 2);
  fs::remove_all(root);
}

}  // namespace
}  // namespace hameritt::map
