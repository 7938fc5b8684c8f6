// Reuse across the scenarios of a batch (issue 14): the planning structures kept per world
// (street index, validated route pieces, inflated obstacles) must never change a scenario's
// bytes. A scenario generated first on a fresh world (empty caches) must equal the same
// scenario generated after a batch on that world (warm caches), and the batch's own files.
// (GeneratorTest.BatchIsByteIdenticalWhateverTheJobCount compares 1, 2 and 5 jobs.)
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "hameritt/scenario/batch.h"
#include "hameritt/scenario/scenario_io.h"
#include "test_util.h"

namespace fs = std::filesystem;
using namespace hameritt::scenario;
using hameritt::scenario::testing::freshTempDir;
using hameritt::scenario::testing::shippedConfig;

namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// A world no other test of this process uses, so that its caches start empty here.
const World& freshWorld() {
  static const World w = [] {
    WorldParams p = loadWorldParams(defaultConfigDir() + "/world.json");
    p.seed = 1414;
    return generateWorld(p);
  }();
  return w;
}

struct Json {
  std::string mission, sim;
};

Json jsonOf(const Scenario& s) { return {missionJson(s.mission), simConfigJson(s.sim)}; }

}  // namespace

TEST(GeneratorReuseTest, ColdAndWarmCachesGiveTheSameBytes) {
  const World& world = freshWorld();
  const GeneratorConfig& config = shippedConfig();
  BatchRequest req;
  req.classes = parseClassList("all");
  req.count = 18;
  req.seed = 1414;
  req.jobs = 2;
  // Cold: the first scenarios of each class, generated before anything else on this world.
  std::vector<Json> cold;
  for (int i = 0; i < 6; ++i) {
    cold.push_back(
        jsonOf(generateScenario(world, config, req.classes[static_cast<std::size_t>(i) % 3],
                                batchSeed(req.seed, static_cast<std::uint64_t>(i)))));
  }
  // The batch on two threads (the caches fill in whatever order the threads run).
  req.out_dir = freshTempDir("reuse_batch");
  const auto entries = generateBatch(world, config, req);
  ASSERT_EQ(entries.size(), 18u);
  int compared = 0;
  for (const auto& e : entries) {
    // Warm: every scenario again, alone, after the batch.
    const Json warm = jsonOf(generateScenario(world, config, e.cls, e.seed));
    const std::string dir = req.out_dir + "/" + e.id;
    EXPECT_EQ(slurp(dir + "/mission.json"), warm.mission) << e.id;
    EXPECT_EQ(slurp(dir + "/sim_config.json"), warm.sim) << e.id;
    if (e.index < 6) {
      EXPECT_EQ(cold[static_cast<std::size_t>(e.index)].mission, warm.mission) << e.id;
      EXPECT_EQ(cold[static_cast<std::size_t>(e.index)].sim, warm.sim) << e.id;
    }
    ++compared;
  }
  EXPECT_EQ(compared, 18);
  // Every class planned routes or perception paths here, so the caches were exercised.
  bool planned = false;
  for (const auto& e : entries) {
    planned =
        planned || slurp(req.out_dir + "/" + e.id + "/sim_config.json").find("perception_path") !=
                       std::string::npos;
  }
  EXPECT_TRUE(planned);
  fs::remove_all(req.out_dir);
}
