// rostest: the scenario_generator node's GenerateScenario service, called as a client would.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "hameritt/GenerateScenario.h"
#include "hameritt/build_paths.h"

namespace fs = std::filesystem;

namespace {

std::string tempDir(const std::string& name) {
  const std::string d = fs::temp_directory_path().string() + "/hameritt_rostest_" + name + "_" +
                        std::to_string(::getpid());
  fs::remove_all(d);
  return d;
}

hameritt::GenerateScenario call(const std::string& cls, unsigned count, std::uint64_t seed,
                                const std::string& out) {
  hameritt::GenerateScenario srv;
  srv.request.scenario_class = cls;
  srv.request.count = count;
  srv.request.seed = seed;
  srv.request.out_dir = out;
  EXPECT_TRUE(ros::service::call("/scenario_generator/generate", srv));
  return srv;
}

}  // namespace

TEST(ScenarioGeneratorService, GeneratesAllClasses) {
  ASSERT_TRUE(ros::service::waitForService("/scenario_generator/generate", ros::Duration(30)));
  const std::string out = tempDir("ok");
  const auto srv = call("all", 6, 11, out);
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(srv.response.code, 0);
  ASSERT_EQ(srv.response.scenario_ids.size(), 6u);
  ASSERT_EQ(srv.response.scenario_dirs.size(), 6u);
  int per_class[3] = {0, 0, 0};
  for (std::size_t i = 0; i < 6; ++i) {
    const std::string dir = srv.response.scenario_dirs[i];
    ASSERT_TRUE(fs::exists(dir + "/mission.json")) << dir;
    ASSERT_TRUE(fs::exists(dir + "/sim_config.json")) << dir;
    std::ifstream in(dir + "/mission.json");
    const auto m = nlohmann::json::parse(in);
    EXPECT_EQ(m["scenario_id"], srv.response.scenario_ids[i]);
    const std::string cls = m["class"];
    per_class[cls == "area_search" ? 0 : cls == "route_search" ? 1 : 2]++;
  }
  EXPECT_EQ(per_class[0], 2);
  EXPECT_EQ(per_class[1], 2);
  EXPECT_EQ(per_class[2], 2);
  EXPECT_TRUE(fs::exists(out + "/manifest.json"));
  // Same request, same ids (deterministic by seed).
  const auto again = call("all", 6, 11, tempDir("again"));
  EXPECT_EQ(again.response.scenario_ids, srv.response.scenario_ids);
  fs::remove_all(out);
}

TEST(ScenarioGeneratorService, RejectsBadRequestsWithCodes) {
  ASSERT_TRUE(ros::service::waitForService("/scenario_generator/generate", ros::Duration(30)));
  auto bad_class = call("street_race", 1, 1, tempDir("bad"));
  EXPECT_FALSE(bad_class.response.success);
  EXPECT_EQ(bad_class.response.code, 2);
  EXPECT_NE(bad_class.response.message.find("street_race"), std::string::npos);

  auto zero = call("pursuit", 0, 1, tempDir("zero"));
  EXPECT_FALSE(zero.response.success);
  EXPECT_EQ(zero.response.code, 2);
  EXPECT_NE(zero.response.message.find("--count"), std::string::npos);

  auto unwritable = call("pursuit", 1, 1, "/proc/hameritt_cannot_write_here");
  EXPECT_FALSE(unwritable.response.success);
  EXPECT_EQ(unwritable.response.code, 2);
  EXPECT_TRUE(unwritable.response.scenario_ids.empty());
}

TEST(ScenarioGeneratorService, GeneratesFromASpec) {
  ASSERT_TRUE(ros::service::waitForService("/scenario_generator/generate", ros::Duration(60)));
  const std::string out = tempDir("spec");
  hameritt::GenerateScenario srv;
  srv.request.spec = std::string(HAMERITT_SOURCE_DIR) + "/scenarios/specs/red_sedan_garage.hspec";
  srv.request.count = 3;
  srv.request.seed = 5;
  srv.request.out_dir = out;
  ASSERT_TRUE(ros::service::call("/scenario_generator/generate", srv));
  EXPECT_EQ(srv.response.code, 0) << srv.response.message;
  ASSERT_EQ(srv.response.scenario_ids.size(), 3u);
  for (const auto& dir : srv.response.scenario_dirs) {
    const auto sim = nlohmann::json::parse(std::ifstream(dir + "/sim_config.json"));
    EXPECT_EQ(sim["spec"]["sampler"], "random");
    const auto m = nlohmann::json::parse(std::ifstream(dir + "/mission.json"));
    EXPECT_EQ(m["objective"]["targets"][0]["color"], "red");
    int right_of_garage = 0;
    for (const auto& r : m["scene_relations"]) {
      right_of_garage += r["operator"] == "RIGHT_OF" && r["related"]["class"] == "garage";
    }
    EXPECT_EQ(right_of_garage, 1);
  }
  // Bad specs and parameters: code 2, nothing written.
  const std::string bad = tempDir("bad_spec.hspec");
  std::ofstream(bad) << "scenario area_search\ntarget car {color: scarlet}\n";
  srv.request.spec = bad;
  srv.request.out_dir = tempDir("spec_bad");
  ASSERT_TRUE(ros::service::call("/scenario_generator/generate", srv));
  EXPECT_EQ(srv.response.code, 2);
  EXPECT_NE(srv.response.message.find("unknown color 'scarlet'"), std::string::npos)
      << srv.response.message;
  EXPECT_FALSE(fs::exists(srv.request.out_dir));
  srv.request.spec = std::string(HAMERITT_SOURCE_DIR) + "/scenarios/specs/red_sedan_garage.hspec";
  srv.request.params = {"snow=1"};
  ASSERT_TRUE(ros::service::call("/scenario_generator/generate", srv));
  EXPECT_EQ(srv.response.code, 2);
  EXPECT_NE(srv.response.message.find("--param: unknown parameter 'snow'"), std::string::npos)
      << srv.response.message;
  EXPECT_FALSE(fs::exists(srv.request.out_dir));
  fs::remove(bad);
  fs::remove_all(out);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "scenario_generator_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
