// Reuse across the scenarios of a batch (issue 14): the planning structures kept per world
// (street index, validated route pieces, inflated obstacles) must never change a scenario's
// bytes. Each scenario of a batch (warm caches, filled by the scenarios before it on either
// thread) must equal the same scenario generated alone on emptied caches.
// (GeneratorTest.BatchIsByteIdenticalWhateverTheJobCount compares 1, 2 and 5 jobs.)
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "hameritt/planning/vehicle_routes.h"
#include "hameritt/generation/batch.h"
#include "hameritt/scenario/scenario_io.h"
#include "test_util.h"

namespace fs = std::filesystem;
using namespace hameritt::scenario;
using hameritt::scenario::testing::freshTempDir;
using hameritt::scenario::testing::slurp;
using hameritt::scenario::testing::shippedConfig;

namespace {


// A world no other test of this process uses, so that its caches start empty here.
const World& freshWorld() {
  static const World w = [] {
    WorldParams p = loadWorldParams(defaultConfigDir() + "/world.json");
    p.seed = 1414;
    return generateWorld(p);
  }();
  return w;
}

}  // namespace

TEST(GeneratorReuseTest, ColdAndWarmCachesGiveTheSameBytes) {
  const World& world = freshWorld();
  const GeneratorConfig& config = shippedConfig();
  BatchRequest req;
  req.classes = parseClassList("all");
  req.count = 30;
  req.seed = 1414;
  req.jobs = 2;
  // Warm: the batch on two threads; each scenario meets the pieces its predecessors (on
  // either thread, in whatever order they ran) left in the caches.
  req.out_dir = freshTempDir("reuse_batch");
  const auto entries = generateBatch(world, config, req);
  ASSERT_EQ(entries.size(), 30u);
  int compared = 0, routes = 0;
  for (const auto& e : entries) {
    // Cold: the scenario alone, on emptied caches.
    hameritt::planning::clearRouteCaches();
    const Scenario s = generateScenario(world, config, e.cls, e.seed);
    const std::string dir = req.out_dir + "/" + e.id;
    EXPECT_EQ(slurp(dir + "/mission.json"), missionJson(s.mission)) << e.id;
    EXPECT_EQ(slurp(dir + "/sim_config.json"), simConfigJson(s.sim)) << e.id;
    ++compared;
    if (e.cls != ScenarioClass::kAreaSearch) ++routes;
  }
  EXPECT_EQ(compared, 30);
  EXPECT_EQ(routes, 20);  // route search and pursuit plan target routes
  fs::remove_all(req.out_dir);
}
