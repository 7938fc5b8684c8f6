// The shared bounds on JSON input (bounded_json.h): nesting deeper than 64 levels and files
// larger than the size limit are ConfigErrors naming the file and the limit, for the shared
// check and for each library reader built on it. Controls: 64 levels and a file at the size
// limit pass the check, so each refusal is the limit's and not another error's.

#include "hameritt/scenario/bounded_json.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/params_table.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/validation.h"
#include "test_util.h"

namespace hameritt::scenario {
namespace {

using testing::messageOf;

namespace fs = std::filesystem;

std::string nested(std::size_t depth) { return std::string(depth, '[') + std::string(depth, ']'); }

long maxRssKb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

TEST(BoundedJsonTest, DepthLimitIsExactAndIgnoresBracketsInStrings) {
  EXPECT_EQ(messageOf([] { checkJsonDepth(nested(kMaxJsonDepth), "a.json"); }), "(no error)");
  EXPECT_EQ(messageOf([] { checkJsonDepth(nested(kMaxJsonDepth + 1), "a.json"); }),
            "a.json: JSON nested deeper than the limit of 64 levels (at byte 64)");
  // Brackets inside strings, escaped quotes included, are not nesting.
  const std::string text = "{\"k\": \"[[[[\\\"{{{{\", \"v\": " + nested(kMaxJsonDepth - 1) + "}";
  EXPECT_EQ(messageOf([&] { checkJsonDepth(text, "a.json", kMaxJsonDepth); }), "(no error)");
  EXPECT_NE(messageOf([&] { checkJsonDepth(text, "a.json", kMaxJsonDepth - 1); }), "(no error)");
}

TEST(BoundedJsonTest, DeepNestingIsRefusedByEveryLibraryReaderInLittleMemory) {
  const std::string deep = nested(100000);
  const long before = maxRssKb();
  const std::string limit = "JSON nested deeper than the limit of 64 levels";
  EXPECT_NE(messageOf([&] { parseMission(deep, "m.json"); }).find("m.json: " + limit),
            std::string::npos);
  EXPECT_NE(messageOf([&] { parseSimConfig(deep, "s.json"); }).find("s.json: " + limit),
            std::string::npos);
  EXPECT_NE(messageOf([&] { parseJsonString(deep, "w.json"); }).find("w.json: " + limit),
            std::string::npos);
  nlohmann::json doc;
  ValidationIssue issue;
  EXPECT_FALSE(parseJsonText(deep, "v.json", &doc, &issue));
  EXPECT_EQ(issue.rule, "limit");
  EXPECT_NE(issue.message.find(limit), std::string::npos) << issue.message;
  // The peak of this process grew by less than 100 MB (without the limit the validator's
  // duplicate-key bookkeeping alone takes gigabytes).
  EXPECT_LT(maxRssKb() - before, 100 * 1024);
}

TEST(BoundedJsonTest, OverSizeFileIsRefusedBeforeItIsRead) {
  const fs::path dir = fs::temp_directory_path() / ("hameritt_bounded_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string big = (dir / "big.json").string();
  {
    std::ofstream out(big);
    out << "[";
  }
  const std::uintmax_t limit = 1 << 20;
  fs::resize_file(big, limit + 1);
  EXPECT_EQ(messageOf([&] { readBoundedFile(big, limit); }),
            big +
                ": 1048577 bytes, more than the limit of 1048576 bytes (1 MiB) for a JSON "
                "document");
  fs::resize_file(big, limit);  // control: at the limit
  EXPECT_EQ(readBoundedFile(big, limit).size(), limit);
  // The library readers at their own limit (a sparse file: no disk used).
  fs::resize_file(big, kMaxJsonFileBytes + 1);
  const std::string stated = "more than the limit of 67108864 bytes (64 MiB)";
  EXPECT_NE(messageOf([&] { loadMission(big); }).find(stated), std::string::npos);
  EXPECT_NE(messageOf([&] { loadSimConfig(big); }).find(stated), std::string::npos);
  EXPECT_NE(messageOf([&] { readJsonFile(big); }).find(stated), std::string::npos);
  const auto issues = validateFile(big, "/nonexistent");
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_EQ(issues[0].rule, "limit");
  EXPECT_NE(issues[0].message.find(stated), std::string::npos) << issues[0].message;
  EXPECT_EQ(messageOf([&] { readBoundedFile((dir / "none.json").string()); }),
            (dir / "none.json").string() + ": cannot open file");
  // A directory opens as a stream whose end is the largest offset: it is named for what it is,
  // not refused as too large.
  EXPECT_EQ(messageOf([&] { readBoundedFile(dir.string()); }),
            dir.string() + ": is a directory, expected a JSON file");
  const auto dir_issues = validateFile(dir.string(), "/nonexistent");
  ASSERT_EQ(dir_issues.size(), 1u);
  EXPECT_EQ(dir_issues[0].rule, "io");
  EXPECT_EQ(dir_issues[0].message, "is a directory, expected a JSON file");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hameritt::scenario
