// Numbers a reader cannot hold: the regressions of the fuzzing campaign (docs/RELIABILITY.md,
// inputs in test/fuzz/regressions/). Integers beyond 64 bits and integer-valued doubles like
// 1e300 are reported as input errors instead of being converted (undefined behaviour, or a
// silent wrap-around that changes the document).

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "hameritt/scenario/error.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/validation.h"
#include "test_util.h"

namespace hameritt::scenario {
namespace {

using testing::messageOf;

std::string regression(const std::string& target, const std::string& name) {
  std::ifstream in(defaultConfigDir() + "/../test/fuzz/regressions/" + target + "/" + name);
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_FALSE(s.str().empty()) << target << "/" << name;
  return s.str();
}

std::vector<ValidationIssue> validateText(const std::string& text) {
  nlohmann::json doc;
  ValidationIssue issue;
  EXPECT_TRUE(parseJsonText(text, "doc.json", &doc, &issue)) << issue.message;
  return validateDocument(doc, "doc.json", defaultConfigDir() + "/schema");
}

bool hasIssue(const std::vector<ValidationIssue>& issues, const std::string& path,
              const std::string& rule) {
  for (const auto& i : issues) {
    if (i.path == path && i.rule == rule) return true;
  }
  return false;
}

TEST(ReaderLimitsTest, AttributeBeyondInt64IsAnErrorNotAWrapAround) {
  const std::string m = regression("mission", "attribute_2pow64.json");
  EXPECT_NE(messageOf([&] { parseMission(m, "m.json"); })
                .find(".attributes.kind: expected a string or an integer within [-2^63, 2^63), "
                      "got number 18446744073709551615"),
            std::string::npos)
      << messageOf([&] { parseMission(m, "m.json"); });
  const std::string s = regression("sim_config", "attribute_2pow64.json");
  EXPECT_NE(messageOf([&] { parseSimConfig(s, "s.json"); })
                .find(".attributes.make: expected a string or an integer"),
            std::string::npos)
      << messageOf([&] { parseSimConfig(s, "s.json"); });
}

TEST(ReaderLimitsTest, StringOverloadsNameTheFile) {
  EXPECT_NE(messageOf([] { parseMission("{", "given.json"); }).find("given.json: malformed JSON"),
            std::string::npos);
  EXPECT_NE(messageOf([] { parseSimConfig("[]", "given.json"); }).find("given.json: (root)"),
            std::string::npos);
}

TEST(ReaderLimitsTest, ManifestSeedBeyond64BitsIsAnIssue) {
  const auto issues = validateText(regression("manifest", "seed_3.8735e83.json"));
  EXPECT_TRUE(hasIssue(issues, "/scenarios/0/id", "scenario_id")) << issues.size();
}

TEST(ReaderLimitsTest, PriorCellRow1e300IsOutsideTheGrid) {
  const auto issues = validateText(regression("manifest", "prior_row_1e300.json"));
  bool found = false;
  for (const auto& i : issues) found = found || i.rule == "prior_cells";
  EXPECT_TRUE(found);
}

TEST(ReaderLimitsTest, SchemaLengthsBeyond64BitsAreSchemaErrors) {
  for (const char* name : {"minlength_1e30.json", "maxitems_2pow64.json"}) {
    const auto schema = nlohmann::json::parse(regression("validator", name));
    EXPECT_THROW(JsonSchema(schema, name), SchemaError) << name;
  }
  // The largest length that fits is still accepted.
  EXPECT_NO_THROW(JsonSchema(nlohmann::json::parse(R"({"maxLength": 18446744073709551615})"), "x"));
}

}  // namespace
}  // namespace hameritt::scenario
