#include "hameritt/scenario/sim_config_io.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "hameritt/scenario/error.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/scenario_io.h"
#include "sim_test_util.h"

namespace hameritt::scenario {
namespace {

using json = nlohmann::ordered_json;

// Empty when equal, else the position and context of the first difference (no huge dumps).
std::string firstDiff(const std::string& a, const std::string& b) {
  if (a == b) return "";
  std::size_t i = 0;
  while (i < a.size() && i < b.size() && a[i] == b[i]) ++i;
  const std::size_t from = i > 80 ? i - 80 : 0;
  return "differ at byte " + std::to_string(i) + ":\n" + a.substr(from, 160) + "\n---\n" +
         b.substr(from, 160);
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const GeneratorConfig& shippedConfig() {
  static const GeneratorConfig c = loadGeneratorConfig(defaultConfigDir() + "/generator.json");
  return c;
}

TEST(SimConfigIo, ShippedScenarioRoundTripsByteForByte) {
  const std::string path = sim::testing::defaultScenarioDir() + "/sim_config.json";
  const std::string text = readFile(path);
  ASSERT_FALSE(text.empty());
  const SimConfig c = loadSimConfig(path);
  EXPECT_EQ(firstDiff(simConfigJson(c), text), "");
  EXPECT_EQ(c.scenario_id, "area_search-00000000000007fc");
  EXPECT_EQ(c.seed, 2044u);
  EXPECT_EQ(c.world_fingerprint, sim::testing::shippedWorld().fingerprint());
  EXPECT_EQ(c.uav.cameras.size(), 2u);
}

TEST(SimConfigIo, GeneratedScenariosRoundTripByteForByte) {
  const World& world = sim::testing::shippedWorld();
  int n = 0;
  for (ScenarioClass cls :
       {ScenarioClass::kAreaSearch, ScenarioClass::kRouteSearch, ScenarioClass::kPursuit}) {
    for (std::uint64_t seed : {1u, 77u, 4242u}) {
      const Scenario s = generateScenario(world, shippedConfig(), cls, seed);
      const std::string text = simConfigJson(s.sim);
      const SimConfig back = simConfigFromJson(json::parse(text), "gen.json");
      EXPECT_EQ(firstDiff(simConfigJson(back), text), "") << toString(cls) << " " << seed;
      // The sorted-key overload reads the same content (attribute order aside).
      const SimConfig sorted = simConfigFromJson(nlohmann::json::parse(text), "gen.json");
      EXPECT_EQ(sorted.entities.size(), back.entities.size());
      ASSERT_EQ(back.entities.size(), s.sim.entities.size());
      for (std::size_t i = 0; i < back.entities.size(); ++i) {
        EXPECT_EQ(back.entities[i].trajectory.size(), s.sim.entities[i].trajectory.size());
        EXPECT_EQ(back.entities[i].entity.attributes, s.sim.entities[i].entity.attributes);
      }
      ++n;
    }
  }
  EXPECT_EQ(n, 9);
}

// Expects the edited document to fail with a message containing every fragment.
void expectError(const std::function<void(json&)>& edit, std::vector<std::string> fragments) {
  const std::string path = sim::testing::defaultScenarioDir() + "/sim_config.json";
  json j = json::parse(readFile(path));
  edit(j);
  try {
    simConfigFromJson(j, "bad_sim_config.json");
    FAIL() << "no error; expected " << fragments.front();
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("bad_sim_config.json"), std::string::npos) << msg;
    for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << msg;
  }
}

TEST(SimConfigIo, ErrorsNameFilePathAndExpectation) {
  expectError([](json& j) { j.erase("duration"); }, {"duration", "missing"});
  expectError([](json& j) { j["duration"] = "long"; }, {"duration", "expected a number"});
  expectError([](json& j) { j["extra"] = 1; }, {"extra", "unknown key"});
  expectError([](json& j) { j["schema"] = "hameritt/mission"; }, {"schema", "hameritt/sim_config"});
  expectError([](json& j) { j["class"] = "dogfight"; }, {"class", "dogfight"});
  expectError([](json& j) { j["seed"] = -4; }, {"seed", "non-negative integer"});
  expectError([](json& j) { j["entities"][2]["class"] = "tank"; }, {"entities[2].class", "tank"});
  expectError([](json& j) { j["entities"][1]["pose"].erase("yaw"); },
              {"entities[1].pose.yaw", "missing"});
  expectError(
      [](json& j) {
        j["entities"][5]["trajectory"][1] = json::array({1, 2, 3});
      },
      {"entities[5].trajectory[1]", "5 numbers"});
  expectError([](json& j) { j["entities"][3]["attributes"]["color"] = 1.5; },
              {"entities[3].attributes.color", "string or an integer"});
  expectError([](json& j) { j["entities"][4]["id"] = j["entities"][0]["id"]; },
              {"entities[4].id", "duplicate"});
  expectError([](json& j) { j["environment"]["wind"]["gust_intensity"] = 2; },
              {"environment.wind.gust_intensity", "[0, 1]"});
  expectError(
      [](json& j) {
        j["environment"]["wind"]["mean"] = json::array({1, 2});
      },
      {"environment.wind.mean", "3 numbers"});
  expectError([](json& j) { j["uav"]["payload"]["cameras"][1]["width"] = 0; },
              {"uav.payload.cameras[1].width"});
  expectError([](json& j) { j["uav"]["start"]["x"] = nullptr; }, {"uav.start.x", "number"});
  expectError([](json& j) { j["world"]["params"]["street_width"] = "wide"; },
              {"world.params.street_width"});
  expectError([](json& j) { j["world"]["fingerprint"] = "xyz"; }, {"world.fingerprint", "hex"});
  expectError([](json& j) { j["perturbations"]["camera_noise"].erase("motion_blur_px"); },
              {"perturbations.camera_noise.motion_blur_px", "missing"});
  EXPECT_THROW(loadSimConfig("/nonexistent/sim_config.json"), ConfigError);
}

}  // namespace
}  // namespace hameritt::scenario
