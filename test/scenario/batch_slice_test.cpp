// Sharded generation: a slice (--first K --count N) of a batch equals, byte for byte, the same
// indices of the whole batch, and its manifest lists the batch indices.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hameritt/generation/batch.h"
#include "hameritt/scenario/error.h"
#include "test_util.h"

namespace fs = std::filesystem;
using namespace hameritt::scenario;
using hameritt::scenario::testing::freshTempDir;
using hameritt::scenario::testing::slurp;
using hameritt::scenario::testing::shippedConfig;
using hameritt::scenario::testing::shippedWorld;

TEST(BatchSliceTest, SlicesEqualTheSameIndicesOfTheWholeBatch) {
  BatchRequest req;
  req.classes = parseClassList("all");
  req.count = 10;
  req.seed = 4242;
  req.jobs = 2;
  req.out_dir = freshTempDir("slice_whole");
  const auto whole = generateBatch(shippedWorld(), shippedConfig(), req);
  const std::string whole_dir = req.out_dir;
  // Uneven shards, one starting at an index that is not a multiple of the class count.
  const int firsts[] = {0, 4, 7};
  const int counts[] = {4, 3, 3};
  int compared = 0;
  for (int s = 0; s < 3; ++s) {
    req.first = firsts[s];
    req.count = counts[s];
    req.out_dir = freshTempDir("slice_" + std::to_string(s));
    const auto part = generateBatch(shippedWorld(), shippedConfig(), req);
    ASSERT_EQ(part.size(), static_cast<std::size_t>(counts[s]));
    for (int i = 0; i < counts[s]; ++i) {
      const ManifestEntry& e = part[static_cast<std::size_t>(i)];
      const ManifestEntry& w = whole[static_cast<std::size_t>(firsts[s] + i)];
      EXPECT_EQ(e.index, w.index);
      EXPECT_EQ(e.id, w.id);
      EXPECT_EQ(e.seed, w.seed);
      EXPECT_EQ(e.cls, w.cls);
      for (const char* f : {"mission.json", "sim_config.json"}) {
        const std::string a = slurp(whole_dir + "/" + w.id + "/" + f);
        ASSERT_FALSE(a.empty()) << w.id << "/" << f;
        EXPECT_EQ(a, slurp(req.out_dir + "/" + e.id + "/" + f)) << e.id << "/" << f;
        ++compared;
      }
    }
    EXPECT_EQ(slurp(whole_dir + "/world.json"), slurp(req.out_dir + "/world.json"));
    const auto m = nlohmann::json::parse(slurp(req.out_dir + "/manifest.json"));
    EXPECT_EQ(m["scenarios"][0]["index"].get<int>(), firsts[s]);
    if (firsts[s] == 0) {
      EXPECT_FALSE(m.contains("first"));  // a batch from 0 keeps its manifest unchanged
    } else {
      EXPECT_EQ(m["first"].get<int>(), firsts[s]);
    }
    fs::remove_all(req.out_dir);
  }
  EXPECT_EQ(compared, 2 * 10);
  fs::remove_all(whole_dir);
}

TEST(BatchSliceTest, RejectsANegativeFirstAndFirstWithAnExactSeed) {
  BatchRequest req;
  req.classes = parseClassList("pursuit");
  req.out_dir = freshTempDir("slice_bad");
  req.first = -1;
  EXPECT_THROW(generateBatch(shippedWorld(), shippedConfig(), req), ConfigError);
  req.first = 3;
  req.exact_seed = true;
  EXPECT_THROW(generateBatch(shippedWorld(), shippedConfig(), req), ConfigError);
  fs::remove_all(req.out_dir);
}
