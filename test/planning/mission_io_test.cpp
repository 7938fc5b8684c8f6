#include "hameritt/build_paths.h"
#include "hameritt/scenario/mission_io.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hameritt/scenario/error.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/scenario_io.h"
#include "../scenario/test_util.h"

namespace hameritt::scenario {
namespace {

using json = nlohmann::ordered_json;
using testing::shippedConfig;
using testing::shippedWorld;

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string errorOf(const json& j) {
  try {
    missionFromJson(j, "m.json");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(MissionIoTest, ShippedMissionRoundTripsByteForByte) {
  const std::string path = std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/mission.json";
  const Mission m = loadMission(path);
  EXPECT_EQ(missionJson(m), readFile(path));
  EXPECT_FALSE(m.kozs.empty());
}

TEST(MissionIoTest, GeneratedMissionsOfEveryClassRoundTripByteForByte) {
  int with_routes = 0, with_windows = 0, eventually = 0;
  for (ScenarioClass cls :
       {ScenarioClass::kAreaSearch, ScenarioClass::kRouteSearch, ScenarioClass::kPursuit}) {
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      const Scenario s = generateScenario(shippedWorld(), shippedConfig(), cls, seed * 7919);
      const std::string text = missionJson(s.mission);
      const Mission back = missionFromJson(json::parse(text), "gen.json");
      ASSERT_EQ(missionJson(back), text) << toString(cls) << " seed " << seed;
      with_routes += !back.routes.empty();
      for (const auto& k : back.kozs) with_windows += !k.window.unbounded();
      for (const auto& r : back.relations) eventually += r.eventually;
    }
  }
  EXPECT_GT(with_routes, 0);
  EXPECT_GT(with_windows, 0);
  (void)eventually;
}

TEST(MissionIoTest, ErrorsNameTheFileThePathAndTheExpectation) {
  const json good = json::parse(
      readFile(std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/mission.json"));
  ASSERT_EQ(errorOf(good), "");
  json j = good;
  j["time_limit"] = "long";
  EXPECT_EQ(errorOf(j), "m.json: time_limit: expected a number, got string \"long\"");
  j = good;
  j["keep_out_zones"][0]["altitude"]["min"] = true;
  EXPECT_EQ(errorOf(j),
            "m.json: keep_out_zones[0].altitude.min: expected a number, got boolean true");
  j = good;
  j["keep_out_zones"][1]["polygon"][2] = json::array({1});
  EXPECT_NE(errorOf(j).find("m.json: keep_out_zones[1].polygon[2]: expected a point [x, y]"),
            std::string::npos);
  j = good;
  j["frame"]["extra"] = 1;
  EXPECT_EQ(errorOf(j), "m.json: frame.extra: unknown key");
  j = good;
  j["areas_of_interest"][0].erase("time_window");
  EXPECT_EQ(errorOf(j), "m.json: areas_of_interest[0].time_window: missing required key");
  j = good;
  j["schema"] = "hameritt/sim_config";
  EXPECT_NE(errorOf(j).find("schema: expected \"hameritt/mission\""), std::string::npos);
  j = good;
  j["keep_out_zones"][0]["time_window"] = {{"net", 50}, {"nlt", 10}};
  EXPECT_NE(errorOf(j).find("keep_out_zones[0].time_window: expected net <= nlt"),
            std::string::npos);
  j = good;
  j["scene_relations"][0]["text"] = "[street] [ON_TOP_OF] [someone_else]";
  EXPECT_NE(errorOf(j).find("scene_relations[0].text: expected \"["), std::string::npos);
  j = good;
  j["scene_relations"][0]["operator"] = "BESIDE";
  EXPECT_NE(errorOf(j).find("scene_relations[0].operator: expected a relation operator"),
            std::string::npos);
  EXPECT_THROW(loadMission("/nonexistent/mission.json"), ConfigError);
}

}  // namespace
}  // namespace hameritt::scenario
