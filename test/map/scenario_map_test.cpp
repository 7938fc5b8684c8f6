// Scenario maps: generated scenarios of every class are drawn and the PNGs checked for size,
// content at known places (keep-out zone tint, target markers), determinism and error handling.

#include "hameritt/map/scenario_map.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "hameritt/scenario/error.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/params_table.h"
#include "hameritt/scenario/scenario_io.h"

namespace hameritt::map {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using scenario::ConfigError;
using scenario::OutputError;
using scenario::ScenarioClass;

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// Mean BGR colour of the (2r+1)^2 patch around p.
cv::Vec3d patchMean(const cv::Mat& img, cv::Point p, int r) {
  cv::Vec3d sum(0, 0, 0);
  int n = 0;
  for (int y = p.y - r; y <= p.y + r; ++y) {
    for (int x = p.x - r; x <= p.x + r; ++x) {
      if (x < 0 || y < 0 || x >= img.cols || y >= img.rows) continue;
      const cv::Vec3b c = img.at<cv::Vec3b>(y, x);
      sum += cv::Vec3d(c[0], c[1], c[2]);
      ++n;
    }
  }
  return n ? sum / n : sum;
}

struct GeneratedScenario {
  ScenarioClass cls;
  std::string dir;
  json mission;
  json sim;
};

class ScenarioMapTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::string config = scenario::defaultConfigDir();
    world_ = std::make_unique<scenario::World>(
        scenario::generateWorld(scenario::loadWorldParams(config + "/world.json")));
    const auto gen = scenario::loadGeneratorConfig(config + "/generator.json");
    root_ = (fs::temp_directory_path() / ("hameritt_map_test_" + std::to_string(::getpid())))
                .string();
    fs::remove_all(root_);
    fs::create_directories(root_ + "/scenarios");
    for (ScenarioClass cls :
         {ScenarioClass::kAreaSearch, ScenarioClass::kRouteSearch, ScenarioClass::kPursuit}) {
      // The first seed that generates (a seed may legitimately fail with GenerationError).
      for (std::uint64_t seed = 1; seed <= 40; ++seed) {
        try {
          const scenario::Scenario s = scenario::generateScenario(*world_, gen, cls, seed);
          GeneratedScenario g;
          g.cls = cls;
          g.dir = scenario::writeScenarioDir(root_ + "/scenarios", s);
          g.mission = scenario::readJsonFile(g.dir + "/mission.json");
          g.sim = scenario::readJsonFile(g.dir + "/sim_config.json");
          scenarios_.push_back(std::move(g));
          break;
        } catch (const scenario::GenerationError&) {
        }
      }
    }
  }

  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(root_, ec);
    scenarios_.clear();
    world_.reset();
  }

  // A fresh copy of a scenario directory that a test may modify.
  static std::string copyScenario(const GeneratedScenario& g, const std::string& name) {
    const std::string dir = root_ + "/" + name;
    fs::remove_all(dir);
    fs::copy(g.dir, dir, fs::copy_options::recursive);
    return dir;
  }

  static const GeneratedScenario& scenarioOf(ScenarioClass cls) {
    for (const auto& g : scenarios_) {
      if (g.cls == cls) return g;
    }
    throw std::runtime_error(std::string("no scenario of class ") + scenario::toString(cls));
  }

  static std::unique_ptr<scenario::World> world_;
  static std::string root_;
  static std::vector<GeneratedScenario> scenarios_;
};

std::unique_ptr<scenario::World> ScenarioMapTest::world_;
std::string ScenarioMapTest::root_;
std::vector<GeneratedScenario> ScenarioMapTest::scenarios_;

TEST_F(ScenarioMapTest, GeneratesOneScenarioOfEachClass) {
  ASSERT_EQ(scenarios_.size(), 3u);
}

TEST_F(ScenarioMapTest, WritesPngOfTheLaidOutSizeCoveringTheMission) {
  ASSERT_EQ(scenarios_.size(), 3u);
  const MapStyle style;
  for (const auto& g : scenarios_) {
    SCOPED_TRACE(g.dir);
    const std::string out = root_ + "/size_" + scenario::toString(g.cls) + ".png";
    writeScenarioMap(g.dir, out, style);
    ASSERT_TRUE(fs::exists(out));
    const cv::Mat img = cv::imread(out, cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty());
    const MapFrame f = computeMapFrame(*world_, g.mission, g.sim, style);
    EXPECT_EQ(img.cols, f.image_size.width);
    EXPECT_EQ(img.rows, f.image_size.height);
    // Map part: the region at the requested scale, beside the panel.
    EXPECT_EQ(f.map_rect.width,
              static_cast<int>(std::ceil((f.region.max.x() - f.region.min.x()) * style.px_per_m)));
    EXPECT_EQ(f.map_rect.height,
              static_cast<int>(std::ceil((f.region.max.y() - f.region.min.y()) * style.px_per_m)));
    EXPECT_EQ(img.cols, f.map_rect.width + style.panel_width_px);
    EXPECT_GT(f.map_rect.y, 20);  // a title above the map
    // The crop keeps every AOI vertex and every target's start inside the map.
    const cv::Rect map = f.map_rect;
    for (const auto& a : g.mission["areas_of_interest"]) {
      for (const auto& v : a["polygon"]) {
        const cv::Point p = f.pixelAt({v[0].get<double>(), v[1].get<double>()});
        EXPECT_TRUE(map.contains(p)) << a["id"];
      }
    }
    for (const auto& e : g.sim["entities"]) {
      if (e["role"] != "target") continue;
      const cv::Point p = f.pixelAt({e["pose"]["x"].get<double>(), e["pose"]["y"].get<double>()});
      EXPECT_TRUE(map.contains(p)) << e["id"];
    }
    EXPECT_LT(fs::file_size(out), 2u * 1024u * 1024u);
  }
}

TEST_F(ScenarioMapTest, FullMapShowsTheWholeWorldAtTheRequestedScale) {
  ASSERT_EQ(scenarios_.size(), 3u);
  MapStyle style;
  style.crop_to_interest = false;
  style.px_per_m = 0.8;
  const auto b = world_->bounds();
  for (const auto& g : scenarios_) {
    SCOPED_TRACE(g.dir);
    const std::string out = root_ + "/full.png";
    writeScenarioMap(g.dir, out, style);
    const cv::Mat img = cv::imread(out, cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty());
    const MapFrame f = computeMapFrame(*world_, g.mission, g.sim, style);
    EXPECT_EQ(img.cols, f.image_size.width);
    EXPECT_EQ(img.rows, f.image_size.height);
    // At least the world plus the margin, more only where the mission sticks out of it.
    EXPECT_LE(f.region.min.x(), b.min.x() - style.margin_m + 1e-9);
    EXPECT_LE(f.region.min.y(), b.min.y() - style.margin_m + 1e-9);
    EXPECT_GE(f.region.max.x(), b.max.x() + style.margin_m - 1e-9);
    EXPECT_GE(f.region.max.y(), b.max.y() + style.margin_m - 1e-9);
    bool inside = true;
    auto check = [&](double x, double y) {
      inside = inside && x >= b.min.x() && x <= b.max.x() && y >= b.min.y() && y <= b.max.y();
      EXPECT_TRUE(f.map_rect.contains(f.pixelAt({x, y}))) << x << ", " << y;
    };
    for (const char* key : {"areas_of_interest", "keep_out_zones"}) {
      for (const auto& a : g.mission[key]) {
        for (const auto& v : a["polygon"]) check(v[0].get<double>(), v[1].get<double>());
      }
    }
    for (const auto& r : g.mission["routes"]) {
      for (const auto& v : r["band_polygon"]) check(v[0].get<double>(), v[1].get<double>());
    }
    // Targets (their paths too) and the UAV start belong to the map as well.
    for (const auto& e : g.sim["entities"]) {
      if (e["role"] != "target") continue;
      check(e["pose"]["x"].get<double>(), e["pose"]["y"].get<double>());
      for (const auto& q : e["trajectory"]) check(q[1].get<double>(), q[2].get<double>());
    }
    check(g.sim["uav"]["start"]["x"].get<double>(), g.sim["uav"]["start"]["y"].get<double>());
    const int map_w = static_cast<int>(std::ceil((f.region.max.x() - f.region.min.x()) * 0.8));
    const int map_h = static_cast<int>(std::ceil((f.region.max.y() - f.region.min.y()) * 0.8));
    EXPECT_EQ(f.map_rect.width, map_w);
    EXPECT_EQ(f.map_rect.height, map_h);
    EXPECT_EQ(img.cols, map_w + style.panel_width_px);
    EXPECT_GE(img.rows, map_h);
    if (inside) {
      const double m = 2 * style.margin_m;
      EXPECT_EQ(map_w, static_cast<int>(std::ceil((b.max.x() - b.min.x() + m) * 0.8)));
      EXPECT_EQ(map_h, static_cast<int>(std::ceil((b.max.y() - b.min.y() + m) * 0.8)));
    }
    // The cropped map of the same scenario is no larger than the full one.
    MapStyle cropped_style = style;
    cropped_style.crop_to_interest = true;
    const MapFrame cropped = computeMapFrame(*world_, g.mission, g.sim, cropped_style);
    EXPECT_LE(cropped.map_rect.width, map_w);
    EXPECT_LE(cropped.map_rect.height, map_h);
  }
}

TEST_F(ScenarioMapTest, KeepOutZonesAreTintedRed) {
  ASSERT_EQ(scenarios_.size(), 3u);
  // The whole world, so that the map is laid out the same with and without the zones.
  MapStyle style;
  style.crop_to_interest = false;
  int checked = 0;
  for (const auto& g : scenarios_) {
    if (g.mission["keep_out_zones"].empty()) continue;
    SCOPED_TRACE(g.dir);
    const cv::Mat with = drawScenarioMap(*world_, g.mission, g.sim, style);
    json bare = g.mission;
    bare["keep_out_zones"] = json::array();
    const cv::Mat without = drawScenarioMap(*world_, bare, g.sim, style);
    const MapFrame f = computeMapFrame(*world_, g.mission, g.sim, style);
    ASSERT_EQ(f.map_rect, computeMapFrame(*world_, bare, g.sim, style).map_rect);
    std::vector<cv::Point> markers;  // targets, confusers, UAV start
    for (const auto& e : g.sim["entities"]) {
      if (e["role"] == "target" || e["role"] == "confuser") {
        markers.push_back(f.pixelAt({e["pose"]["x"].get<double>(), e["pose"]["y"].get<double>()}));
      }
    }
    const auto& start = g.sim["uav"]["start"];
    markers.push_back(f.pixelAt({start["x"].get<double>(), start["y"].get<double>()}));
    for (const auto& k : g.mission["keep_out_zones"]) {
      std::vector<geometry::Vec2> pts;
      for (const auto& v : k["polygon"]) pts.emplace_back(v[0].get<double>(), v[1].get<double>());
      const cv::Point c = f.pixelAt(geometry::Polygon(pts).centroid());
      bool near_marker = false;
      for (const auto& m : markers) near_marker = near_marker || cv::norm(m - c) < 20.0;
      if (near_marker) continue;
      const cv::Vec3d before = patchMean(without, c, 2);
      const cv::Vec3d after = patchMean(with, c, 2);
      // Where the map was already red there (a target's path), the tint cannot be told apart.
      if (before[2] > before[1] + 30 && before[2] > before[0] + 30) continue;
      SCOPED_TRACE(k["id"].get<std::string>());
      EXPECT_GT(after[2], after[1] + 30);  // BGR: red dominates green ...
      EXPECT_GT(after[2], after[0] + 30);  // ... and blue
      EXPECT_GT(after[2] - 0.5 * (after[0] + after[1]), before[2] - 0.5 * (before[0] + before[1]));
      ++checked;
    }
  }
  EXPECT_GT(checked, 0) << "no keep-out zone centroid could be checked";
}

TEST_F(ScenarioMapTest, TargetsCarryTheTargetMarker) {
  ASSERT_EQ(scenarios_.size(), 3u);
  const MapStyle style;
  for (const auto& g : scenarios_) {
    SCOPED_TRACE(g.dir);
    const std::string out = root_ + "/targets_" + scenario::toString(g.cls) + ".png";
    writeScenarioMap(g.dir, out, style);
    const cv::Mat img = cv::imread(out, cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty());
    const MapFrame f = computeMapFrame(*world_, g.mission, g.sim, style);
    const cv::Vec3b want(static_cast<uchar>(kTargetColor[0]), static_cast<uchar>(kTargetColor[1]),
                         static_cast<uchar>(kTargetColor[2]));
    int targets = 0;
    for (const auto& e : g.sim["entities"]) {
      if (e["role"] != "target") continue;
      ++targets;
      const cv::Point p = f.pixelAt({e["pose"]["x"].get<double>(), e["pose"]["y"].get<double>()});
      ASSERT_TRUE(cv::Rect(0, 0, img.cols, img.rows).contains(p));
      EXPECT_EQ(img.at<cv::Vec3b>(p), want) << e["id"];
      // A ring of another colour (white) surrounds the fill (a neighbouring target in a
      // convoy may cover one side of it).
      int ring = 0;
      for (const cv::Point d : {cv::Point(10, 0), cv::Point(-10, 0), cv::Point(0, 10),
                                cv::Point(0, -10)}) {
        ring += img.at<cv::Vec3b>(p + d) != want ? 1 : 0;
      }
      EXPECT_GE(ring, 2) << e["id"];
    }
    EXPECT_GE(targets, 1);
  }
}

TEST_F(ScenarioMapTest, IsDeterministic) {
  ASSERT_FALSE(scenarios_.empty());
  const MapStyle style;
  for (const auto& g : scenarios_) {
    const std::string a = root_ + "/det_a.png", b = root_ + "/det_b.png";
    writeScenarioMap(g.dir, a, style);
    writeScenarioMap(g.dir, b, style);
    const std::string bytes = readBytes(a);
    EXPECT_GT(bytes.size(), 1000u);
    EXPECT_EQ(bytes, readBytes(b)) << g.dir;
  }
  // Different scenarios give different maps.
  const std::string a = root_ + "/det_a.png", b = root_ + "/det_b.png";
  writeScenarioMap(scenarios_.front().dir, a, style);
  writeScenarioMap(scenarios_.back().dir, b, style);
  EXPECT_NE(readBytes(a), readBytes(b));
}

TEST_F(ScenarioMapTest, TamperedFingerprintIsAConfigError) {
  const auto& g = scenarioOf(ScenarioClass::kAreaSearch);
  const std::string dir = copyScenario(g, "tampered");
  json sim = g.sim;
  sim["world"]["fingerprint"] = "0123456789abcdef";
  writeText(dir + "/sim_config.json", sim.dump());
  try {
    writeScenarioMap(dir, root_ + "/tampered.png", MapStyle());
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("sim_config.json"), std::string::npos) << what;
    EXPECT_NE(what.find("world.fingerprint"), std::string::npos) << what;
  }
  EXPECT_FALSE(fs::exists(root_ + "/tampered.png"));
}

TEST_F(ScenarioMapTest, MissingOrMalformedInputIsAConfigError) {
  const auto& g = scenarioOf(ScenarioClass::kAreaSearch);
  const std::string dir = copyScenario(g, "broken");
  fs::remove(dir + "/mission.json");
  try {
    writeScenarioMap(dir, root_ + "/broken.png", MapStyle());
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("mission.json"), std::string::npos) << e.what();
  }
  // A malformed field is reported with its JSON path.
  json mission = g.mission;
  mission["areas_of_interest"][0]["polygon"] = "not a polygon";
  writeText(dir + "/mission.json", mission.dump());
  try {
    writeScenarioMap(dir, root_ + "/broken.png", MapStyle());
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("mission.json"), std::string::npos) << what;
    EXPECT_NE(what.find("areas_of_interest[0].polygon"), std::string::npos) << what;
  }
  // A missing sim_config field, likewise.
  writeText(dir + "/mission.json", g.mission.dump());
  json sim = g.sim;
  sim["uav"].erase("start");
  writeText(dir + "/sim_config.json", sim.dump());
  try {
    writeScenarioMap(dir, root_ + "/broken.png", MapStyle());
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("uav.start"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(root_ + "/broken.png"));
  // A bad style.
  MapStyle bad;
  bad.px_per_m = 0.0;
  EXPECT_THROW(drawScenarioMap(*world_, g.mission, g.sim, bad), ConfigError);
}

TEST_F(ScenarioMapTest, UnwritableOutputIsAnOutputError) {
  ASSERT_FALSE(scenarios_.empty());
  const auto& g = scenarios_.front();
  EXPECT_THROW(writeScenarioMap(g.dir, root_ + "/no/such/dir/map.png", MapStyle()), OutputError);
  // An existing directory where the file should go.
  const std::string taken = root_ + "/taken.png";
  fs::create_directories(taken);
  EXPECT_THROW(writeScenarioMap(g.dir, taken, MapStyle()), OutputError);
  EXPECT_TRUE(fs::is_directory(taken));
  // No temporary file is left behind.
  for (const auto& entry : fs::directory_iterator(root_)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos)
        << entry.path();
  }
}

}  // namespace
}  // namespace hameritt::map
