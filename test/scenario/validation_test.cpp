// Scenario document validation: generated documents pass; targeted mutations fail with the
// right rule at the right JSON path; the schema validator itself honours its keywords and
// refuses keywords it does not implement.

#include "hameritt/scenario/validation.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "hameritt/generation/batch.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/scenario_io.h"

namespace hameritt::scenario {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

std::string schemaDir() { return defaultConfigDir() + "/schema"; }

std::string describe(const std::vector<ValidationIssue>& issues) {
  std::ostringstream os;
  for (const auto& i : issues) os << "  " << formatIssue(i) << "\n";
  return os.str();
}

bool hasIssue(const std::vector<ValidationIssue>& issues, const std::string& rule,
              const std::string& path) {
  for (const auto& i : issues) {
    if (i.rule == rule && i.path == path) return true;
  }
  return false;
}

#define EXPECT_ISSUE(issues, rule, path)                                                      \
  EXPECT_TRUE(hasIssue(issues, rule, path))                                                   \
      << "expected " << rule << " at " << path << ", got " << issues.size() << " issue(s):\n" \
      << describe(issues)

// A temporary directory removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    char tmpl[] = "/tmp/hameritt_validation_XXXXXX";
    const char* d = ::mkdtemp(tmpl);
    if (!d) throw std::runtime_error("mkdtemp failed");
    path_ = d;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }
  std::string write(const std::string& name, const std::string& content) const {
    const std::string p = path_ + "/" + name;
    std::ofstream(p) << content;
    return p;
  }

 private:
  std::string path_;
};

class ValidationTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    world_ =
        std::make_unique<World>(generateWorld(loadWorldParams(defaultConfigDir() + "/world.json")));
    config_ = std::make_unique<GeneratorConfig>(
        loadGeneratorConfig(defaultConfigDir() + "/generator.json"));
  }
  static void TearDownTestSuite() {
    world_.reset();
    config_.reset();
  }

  static Scenario scenario(ScenarioClass cls, std::uint64_t seed) {
    return generateScenario(*world_, *config_, cls, seed);
  }
  static json mission(ScenarioClass cls, std::uint64_t seed) {
    return json::parse(missionJson(scenario(cls, seed).mission));
  }
  static json sim(ScenarioClass cls, std::uint64_t seed) {
    return json::parse(simConfigJson(scenario(cls, seed).sim));
  }
  // The first seed whose document satisfies `want` (the test fails when none of 1..60 does).
  static json find(ScenarioClass cls, bool mission_doc,
                   const std::function<bool(const json&)>& want) {
    for (std::uint64_t seed = 1; seed <= 60; ++seed) {
      json d = mission_doc ? mission(cls, seed) : sim(cls, seed);
      if (want(d)) return d;
    }
    ADD_FAILURE() << "no seed in 1..60 gives the document this test needs";
    return json::object();
  }

  static std::vector<ValidationIssue> check(const json& doc) {
    return validateDocument(doc, "doc.json", schemaDir());
  }

  static std::unique_ptr<World> world_;
  static std::unique_ptr<GeneratorConfig> config_;
};

std::unique_ptr<World> ValidationTest::world_;
std::unique_ptr<GeneratorConfig> ValidationTest::config_;

// ------------------------------------------------------------------ valid documents

TEST_F(ValidationTest, GeneratedDocumentsOfEveryClassAreValid) {
  int checked = 0;
  for (ScenarioClass cls :
       {ScenarioClass::kAreaSearch, ScenarioClass::kRouteSearch, ScenarioClass::kPursuit}) {
    for (std::uint64_t seed : {1ULL, 2ULL, 3ULL, 17ULL, 1234ULL, 0xFFFFFFFFFFFFFFFFULL}) {
      const Scenario s = scenario(cls, seed);
      const auto m = check(json::parse(missionJson(s.mission)));
      EXPECT_TRUE(m.empty()) << toString(cls) << " seed " << seed << " mission:\n" << describe(m);
      const auto c = check(json::parse(simConfigJson(s.sim)));
      EXPECT_TRUE(c.empty()) << toString(cls) << " seed " << seed << " sim_config:\n"
                             << describe(c);
      checked += 2;
    }
  }
  EXPECT_EQ(checked, 36);
}

TEST_F(ValidationTest, WorldDocumentIsValid) {
  const auto issues = check(json::parse(worldJson(*world_)));
  EXPECT_TRUE(issues.empty()) << describe(issues);
}

TEST_F(ValidationTest, WrittenBatchFilesAreValid) {
  TempDir dir;
  BatchRequest req;
  req.classes = parseClassList("all");
  req.count = 4;
  req.seed = 99;
  req.out_dir = dir.path();
  const auto entries = generateBatch(*world_, *config_, req);
  std::vector<std::string> files = {dir.path() + "/manifest.json", dir.path() + "/world.json"};
  for (const auto& e : entries) {
    files.push_back(dir.path() + "/" + e.id + "/mission.json");
    files.push_back(dir.path() + "/" + e.id + "/sim_config.json");
  }
  for (const auto& f : files) {
    const auto issues = validateFile(f, schemaDir());
    EXPECT_TRUE(issues.empty()) << describe(issues);
  }
}

// ------------------------------------------------------------------ schema violations

TEST_F(ValidationTest, WrongTypeIsReportedAtItsPath) {
  json m = mission(ScenarioClass::kAreaSearch, 5);
  m["time_limit"] = "600";
  auto issues = check(m);
  EXPECT_ISSUE(issues, "type", "/time_limit");

  json s = sim(ScenarioClass::kPursuit, 5);
  s["entities"][0]["size"][1] = "wide";
  s["uav"]["payload"]["cameras"][0]["width"] = 640.5;  // "integer" rejects a fraction
  issues = check(s);
  EXPECT_ISSUE(issues, "type", "/entities/0/size/1");
  EXPECT_ISSUE(issues, "type", "/uav/payload/cameras/0/width");
}

TEST_F(ValidationTest, MissingRequiredKeyIsReportedOnItsObject) {
  json m = mission(ScenarioClass::kRouteSearch, 2);
  m["objective"].erase("text");
  auto issues = check(m);
  ASSERT_EQ(issues.size(), 1u) << describe(issues);
  EXPECT_ISSUE(issues, "required", "/objective");
  EXPECT_NE(issues[0].message.find("'text'"), std::string::npos);

  json s = sim(ScenarioClass::kAreaSearch, 2);
  s.erase("perturbations");
  issues = check(s);
  EXPECT_ISSUE(issues, "required", "");
}

TEST_F(ValidationTest, UnknownKeyIsReportedAtTheKey) {
  json m = mission(ScenarioClass::kAreaSearch, 3);
  m["areas_of_interest"][0]["colour"] = "red";
  m["frame"]["origin"]["datum"] = "WGS84";
  auto issues = check(m);
  EXPECT_ISSUE(issues, "additionalProperties", "/areas_of_interest/0/colour");
  EXPECT_ISSUE(issues, "additionalProperties", "/frame/origin/datum");

  json s = sim(ScenarioClass::kAreaSearch, 3);
  s["world"]["params"]["river_width"] = 12.0;
  issues = check(s);
  EXPECT_ISSUE(issues, "additionalProperties", "/world/params/river_width");
  // The schema already explains it; the world-parameter loader does not repeat it.
  EXPECT_FALSE(hasIssue(issues, "world_params", "/world/params")) << describe(issues);
}

TEST_F(ValidationTest, EnumsConstsAndRangesAreEnforced) {
  json m = mission(ScenarioClass::kAreaSearch, 4);
  m["class"] = "area-search";
  m["schema_version"] = 2;
  m["keep_out_zones"][0]["purpose"] = "no_fly";
  m["area_priors"][0]["cells"][0]["probability"] = 1.5;
  m["seed"] = -4;
  auto issues = check(m);
  EXPECT_ISSUE(issues, "enum", "/class");
  EXPECT_ISSUE(issues, "const", "/schema_version");
  EXPECT_ISSUE(issues, "enum", "/keep_out_zones/0/purpose");
  EXPECT_ISSUE(issues, "maximum", "/area_priors/0/cells/0/probability");
  EXPECT_ISSUE(issues, "minimum", "/seed");

  json s = sim(ScenarioClass::kPursuit, 4);
  s["entities"][0]["role"] = "bystander";
  s["entities"][0]["class"] = "bicycle";
  s["entities"][0]["size"][2] = 0.0;
  s["uav"]["payload"]["cameras"][0]["modalities"] = json::array({"rgb", "thermal"});
  s["environment"]["fog"] = 1.2;
  issues = check(s);
  EXPECT_ISSUE(issues, "enum", "/entities/0/role");
  EXPECT_ISSUE(issues, "enum", "/entities/0/class");
  EXPECT_ISSUE(issues, "exclusiveMinimum", "/entities/0/size/2");
  EXPECT_ISSUE(issues, "enum", "/uav/payload/cameras/0/modalities/1");
  EXPECT_ISSUE(issues, "maximum", "/environment/fog");
}

TEST_F(ValidationTest, PointsAndTrajectorySamplesHaveFixedArity) {
  json m = mission(ScenarioClass::kAreaSearch, 6);
  m["areas_of_interest"][0]["polygon"][1] = json::array({1.0, 2.0, 3.0});
  auto issues = check(m);
  EXPECT_ISSUE(issues, "maxItems", "/areas_of_interest/0/polygon/1");

  json s = find(ScenarioClass::kPursuit, false,
                [](const json& d) { return !d["entities"][0]["trajectory"].empty(); });
  s["entities"][0]["trajectory"][0].erase(4);
  issues = check(s);
  EXPECT_ISSUE(issues, "minItems", "/entities/0/trajectory/0");
}

// ------------------------------------------------------------------ semantic rules

TEST_F(ValidationTest, BowTiePolygonIsNotSimple) {
  json m = mission(ScenarioClass::kAreaSearch, 7);
  json& poly = m["areas_of_interest"][0]["polygon"];
  ASSERT_EQ(poly.size(), 4u);
  std::swap(poly[1], poly[2]);  // v0 v2 v1 v3: the edges v0-v2 and v1-v3 cross
  auto issues = check(m);
  ASSERT_EQ(issues.size(), 1u) << describe(issues);
  EXPECT_ISSUE(issues, "polygon_simple", "/areas_of_interest/0/polygon");
}

TEST_F(ValidationTest, OpenOrExplicitlyClosedPolygonIsRejected) {
  json m = mission(ScenarioClass::kAreaSearch, 8);
  json& koz = m["keep_out_zones"][0]["polygon"];
  koz.push_back(koz[0]);  // rings close implicitly: repeating the first vertex is an error
  json& aoi = m["areas_of_interest"][0]["polygon"];
  aoi.erase(2);
  aoi.erase(2);  // two points: an open line, not an area
  auto issues = check(m);
  EXPECT_ISSUE(issues, "polygon_simple", "/keep_out_zones/0/polygon");
  EXPECT_ISSUE(issues, "minItems", "/areas_of_interest/0/polygon");

  json r = mission(ScenarioClass::kRouteSearch, 8);
  json& band = r["routes"][0]["band_polygon"];
  band[2] = band[0];  // a zero-length edge folds the band
  band[1] = band[0];
  issues = check(r);
  EXPECT_ISSUE(issues, "polygon_simple", "/routes/0/band_polygon");
}

TEST_F(ValidationTest, DuplicateIdsAreReported) {
  json m = mission(ScenarioClass::kAreaSearch, 9);
  m["keep_out_zones"].push_back(m["keep_out_zones"][0]);
  const std::string dup =
      "/keep_out_zones/" + std::to_string(m["keep_out_zones"].size() - 1) + "/id";
  json& cells = m["area_priors"][0]["cells"];
  cells[1]["id"] = cells[0]["id"];
  auto issues = check(m);
  EXPECT_ISSUE(issues, "unique_id", dup);
  EXPECT_ISSUE(issues, "unique_id", "/area_priors/0/cells/1/id");

  json s = sim(ScenarioClass::kRouteSearch, 9);
  s["entities"][2]["id"] = s["entities"][1]["id"];
  issues = check(s);
  EXPECT_ISSUE(issues, "unique_id", "/entities/2/id");
}

TEST_F(ValidationTest, InvertedTimeWindowAndAltitudeAreReported) {
  json m = mission(ScenarioClass::kAreaSearch, 10);
  m["areas_of_interest"][0]["time_window"] = {{"net", 300.0}, {"nlt", 120.0}};
  m["keep_out_zones"][0]["altitude"] = {{"min", 80.0}, {"max", 20.0}};
  auto issues = check(m);
  EXPECT_ISSUE(issues, "time_window", "/areas_of_interest/0/time_window");
  EXPECT_ISSUE(issues, "altitude", "/keep_out_zones/0/altitude");

  m["areas_of_interest"][0]["time_window"] = {{"net", 120.0}, {"nlt", 120.0}};  // one instant
  m["keep_out_zones"][0]["altitude"] = {{"min", 20.0}};
  EXPECT_TRUE(check(m).empty()) << describe(check(m));

  json s = sim(ScenarioClass::kPursuit, 10);
  s["uav"]["altitude"]["min"] = 200.0;
  issues = check(s);
  EXPECT_ISSUE(issues, "altitude", "/uav/altitude");
}

TEST_F(ValidationTest, PriorsMustSumToOneAndMatchTheirGrid) {
  json m = mission(ScenarioClass::kAreaSearch, 11);
  json& cells = m["area_priors"][0]["cells"];
  cells[0]["probability"] = cells[0]["probability"].get<double>() + 0.01;
  auto issues = check(m);
  ASSERT_EQ(issues.size(), 1u) << describe(issues);
  EXPECT_ISSUE(issues, "prior_sum", "/area_priors/0/cells");

  json n = mission(ScenarioClass::kAreaSearch, 11);
  n["area_priors"][0]["cells"].erase(0);
  n["area_priors"][0]["aoi_id"] = "aoi_9";
  issues = check(n);
  EXPECT_ISSUE(issues, "prior_cells", "/area_priors/0/cells");
  EXPECT_ISSUE(issues, "prior_aoi", "/area_priors/0/aoi_id");

  json o = mission(ScenarioClass::kAreaSearch, 11);
  o["area_priors"][0]["cells"][0]["row"] = 7;
  issues = check(o);
  EXPECT_ISSUE(issues, "prior_cells", "/area_priors/0/cells/0");
}

TEST_F(ValidationTest, BadRelationOperatorIsRejected) {
  json m = find(ScenarioClass::kAreaSearch, true,
                [](const json& d) { return d["scene_relations"].size() >= 2; });
  m["scene_relations"][0]["operator"] = "EVENTUALLY_PART_OF";  // membership has no temporal form
  m["scene_relations"][1]["operator"] = "NEAR";
  auto issues = check(m);
  EXPECT_ISSUE(issues, "enum", "/scene_relations/0/operator");
  EXPECT_ISSUE(issues, "enum", "/scene_relations/1/operator");
}

TEST_F(ValidationTest, RelationTargetsAndEvidenceAreChecked) {
  json m = find(ScenarioClass::kPursuit, true, [](const json& d) {
    bool part_of = false, spatial = false;
    for (const auto& r : d["scene_relations"]) {
      part_of = part_of || r["operator"] == "PART_OF";
      spatial = spatial || r["operator"] == "NEXT_TO";
    }
    return part_of && spatial;
  });
  std::size_t part_of = 0, spatial = 0;
  for (std::size_t i = 0; i < m["scene_relations"].size(); ++i) {
    if (m["scene_relations"][i]["operator"] == "PART_OF") part_of = i;
    if (m["scene_relations"][i]["operator"] == "NEXT_TO") spatial = i;
  }
  m["scene_relations"][part_of]["target"] = "car_0";
  m["scene_relations"][part_of]["evidence"]["distance"] = 1.0;
  m["scene_relations"][spatial]["evidence"]["time"] = 3.0;
  m["scene_relations"][spatial]["related"]["class"] = "group";
  const std::string pp = "/scene_relations/" + std::to_string(part_of);
  const std::string sp = "/scene_relations/" + std::to_string(spatial);
  auto issues = check(m);
  EXPECT_ISSUE(issues, "relation_target", pp + "/target");
  EXPECT_ISSUE(issues, "relation_evidence", pp + "/evidence");
  EXPECT_ISSUE(issues, "relation_evidence", sp + "/evidence");
  EXPECT_ISSUE(issues, "relation_operator", sp + "/operator");
}

TEST_F(ValidationTest, NonIncreasingTrajectoryIsReported) {
  json s = sim(ScenarioClass::kRouteSearch, 12);
  std::size_t e = 0;
  while (e < s["entities"].size() && s["entities"][e]["trajectory"].size() < 3) ++e;
  ASSERT_LT(e, s["entities"].size());
  json& traj = s["entities"][e]["trajectory"];
  traj[2][0] = traj[1][0];
  auto issues = check(s);
  ASSERT_EQ(issues.size(), 1u) << describe(issues);
  EXPECT_ISSUE(issues, "trajectory_order", "/entities/" + std::to_string(e) + "/trajectory/2");
}

TEST_F(ValidationTest, PerceptionPathOrderTargetsAndStatusAreChecked) {
  json s = sim(ScenarioClass::kPursuit, 12);
  ASSERT_TRUE(s["uav"].contains("perception_path"));
  json& pp = s["uav"]["perception_path"];
  ASSERT_GE(pp["trajectory"].size(), 3u);
  pp["trajectory"][2][0] = pp["trajectory"][1][0];
  pp["targets_seen"].push_back("car_99999");
  auto issues = check(s);
  ASSERT_EQ(issues.size(), 2u) << describe(issues);
  EXPECT_ISSUE(issues, "trajectory_order", "/uav/perception_path/trajectory/2");
  const std::size_t last = pp["targets_seen"].size() - 1;
  EXPECT_ISSUE(issues, "reference", "/uav/perception_path/targets_seen/" + std::to_string(last));
  json bad = sim(ScenarioClass::kPursuit, 12);
  bad["uav"]["perception_path"]["status"] = "great";
  EXPECT_FALSE(check(bad).empty());
}

TEST_F(ValidationTest, GroupMembersAndWorldParamsAreChecked) {
  json s = find(ScenarioClass::kPursuit, false, [](const json& d) { return !d["groups"].empty(); });
  s["groups"][0]["members"][0] = "car_9999";
  s["world"]["params"]["street_width"] = 5.0;  // positive, but too narrow for the generator
  auto issues = check(s);
  EXPECT_ISSUE(issues, "group_member", "/groups/0/members/0");
  EXPECT_ISSUE(issues, "world_params", "/world/params");
}

TEST_F(ValidationTest, ScenarioIdMustMatchClassAndSeed) {
  json m = mission(ScenarioClass::kPursuit, 13);
  m["seed"] = 14;
  auto issues = check(m);
  ASSERT_EQ(issues.size(), 1u) << describe(issues);
  EXPECT_ISSUE(issues, "scenario_id", "/scenario_id");
}

TEST_F(ValidationTest, ManifestAndWorldReferencesAreChecked) {
  TempDir dir;
  BatchRequest req;
  req.classes = parseClassList("area_search,pursuit");
  req.count = 3;
  req.seed = 5;
  req.out_dir = dir.path();
  generateBatch(*world_, *config_, req);
  json man = json::parse(std::ifstream(dir.path() + "/manifest.json"));
  ASSERT_TRUE(check(man).empty()) << describe(check(man));
  man["scenarios"][1]["index"] = 5;
  man["scenarios"][2]["class"] = "pursuit";  // classes[2 % 2] is area_search
  man["count"] = 4;
  auto issues = check(man);
  EXPECT_ISSUE(issues, "manifest_index", "/scenarios/1/index");
  EXPECT_ISSUE(issues, "manifest_class", "/scenarios/2/class");
  EXPECT_ISSUE(issues, "scenario_id", "/scenarios/2/id");
  EXPECT_ISSUE(issues, "manifest_count", "/scenarios");

  json w = json::parse(worldJson(*world_));
  w["streets"]["edges"][0]["entity"] = "house_1";
  w["streets"]["edges"][1]["b"] = static_cast<int>(w["streets"]["nodes"].size());
  issues = check(w);
  EXPECT_ISSUE(issues, "reference", "/streets/edges/0/entity");
  EXPECT_ISSUE(issues, "reference", "/streets/edges/1/b");
}

// ------------------------------------------------------------------ document kinds and files

TEST_F(ValidationTest, UnknownOrMissingSchemaKindIsAnIssue) {
  json m = mission(ScenarioClass::kAreaSearch, 14);
  m["schema"] = "hameritt/missions";
  auto issues = check(m);
  ASSERT_EQ(issues.size(), 1u) << describe(issues);
  EXPECT_ISSUE(issues, "schema_kind", "/schema");

  m.erase("schema");
  issues = check(m);
  ASSERT_EQ(issues.size(), 1u) << describe(issues);
  EXPECT_ISSUE(issues, "schema_kind", "");

  issues = check(json::array({1, 2}));
  EXPECT_ISSUE(issues, "schema_kind", "");
}

TEST_F(ValidationTest, MalformedJsonIsOneIssueWithLineAndColumn) {
  TempDir dir;
  const std::string f =
      dir.write("broken.json", "{\n  \"schema\": \"hameritt/mission\",\n  \"seed\": 1,,\n}\n");
  auto issues = validateFile(f, schemaDir());
  ASSERT_EQ(issues.size(), 1u) << describe(issues);
  EXPECT_EQ(issues[0].rule, "json");
  EXPECT_EQ(issues[0].file, f);
  EXPECT_NE(issues[0].message.find("line 3, column 13"), std::string::npos) << issues[0].message;

  const std::string dup =
      dir.write("dup.json", "{\"schema\": \"hameritt/mission\", \"a\": {\"b\": 1, \"b\": 2}}");
  issues = validateFile(dup, schemaDir());
  ASSERT_EQ(issues.size(), 1u) << describe(issues);
  EXPECT_ISSUE(issues, "json", "/a/b");

  issues = validateFile(dir.path() + "/missing.json", schemaDir());
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_EQ(issues[0].rule, "io");
}

TEST_F(ValidationTest, FormatIssueIsFilePathRuleMessage) {
  EXPECT_EQ(formatIssue({"a.json", "/x/0", "type", "expected number"}),
            "a.json: /x/0: type: expected number");
  EXPECT_EQ(formatIssue({"a.json", "", "json", "bad"}), "a.json: (root): json: bad");
  EXPECT_EQ(jsonPointerAppend("/a", "b/c~d"), "/a/b~1c~0d");
}

TEST_F(ValidationTest, SchemaWithUnsupportedKeywordIsAnIssueNotIgnored) {
  TempDir dir;
  json schema = json::parse(std::ifstream(schemaDir() + "/mission.schema.json"));
  schema["properties"]["scenario_id"] = {{"type", "string"}, {"format", "uuid"}};
  std::ofstream(dir.path() + "/mission.schema.json") << schema.dump();
  const auto issues =
      validateDocument(mission(ScenarioClass::kAreaSearch, 1), "doc.json", dir.path());
  ASSERT_EQ(issues.size(), 1u) << describe(issues);
  EXPECT_EQ(issues[0].rule, "schema");
  EXPECT_EQ(issues[0].file, dir.path() + "/mission.schema.json");
  EXPECT_EQ(issues[0].path, "/properties/scenario_id/format");
}

// ------------------------------------------------------------------ the schema validator

TEST(JsonSchemaTest, RejectsKeywordsItDoesNotImplement) {
  EXPECT_THROW(JsonSchema(json{{"type", "object"}, {"patternProperties", json::object()}}, "s"),
               SchemaError);
  EXPECT_THROW(JsonSchema(json{{"allOf", json::array({json::object()})}}, "s"), SchemaError);
  EXPECT_THROW(JsonSchema(json{{"items", json::array({json::object()})}}, "s"), SchemaError);
  EXPECT_THROW(JsonSchema(json{{"type", "float"}}, "s"), SchemaError);
  EXPECT_THROW(JsonSchema(json{{"exclusiveMinimum", true}}, "s"), SchemaError);  // draft-04 form
  EXPECT_THROW(JsonSchema(json{{"pattern", "("}}, "s"), SchemaError);
  // $ref siblings are ignored by draft-07, so they are refused rather than silently dropped.
  const json sib = json::parse(R"({"definitions": {"a": {"type": "string"}},
                                   "$ref": "#/definitions/a", "minLength": 2})");
  EXPECT_THROW(JsonSchema(sib, "s"), SchemaError);
  try {
    JsonSchema(json::parse(R"({"properties": {"p": {"$ref": "#/definitions/none"}}})"), "s");
    FAIL() << "unresolvable $ref accepted";
  } catch (const SchemaError& e) {
    EXPECT_EQ(e.path(), "/properties/p/$ref");
  }
}

TEST(JsonSchemaTest, ImplementsItsKeywords) {
  const JsonSchema s(json::parse(R"({
    "definitions": {"pos": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 10}},
    "type": "object",
    "required": ["n"],
    "additionalProperties": {"type": ["integer", "null"]},
    "properties": {
      "n": {"type": "integer", "minimum": 1, "maximum": 3},
      "p": {"$ref": "#/definitions/pos"},
      "s": {"type": "string", "pattern": "b+", "minLength": 2, "maxLength": 4},
      "a": {"type": "array", "uniqueItems": true, "items": {"enum": [1, 2, "x"]}},
      "c": {"const": {"k": [1]}},
      "any": {"anyOf": [{"type": "string"}, {"type": "integer"}]},
      "one": {"oneOf": [{"type": "number"}, {"type": "integer"}]},
      "no": false
    }
  })"),
                     "s");
  EXPECT_TRUE(s.validate(json::parse(R"({"n": 2.0, "p": 9.5, "s": "abb", "a": [1, "x"],
      "c": {"k": [1]}, "any": 3, "one": 1.5, "extra": null, "more": 7})"))
                  .empty());

  auto rules = [&](const char* doc) {
    std::vector<std::string> out;
    for (const auto& i : s.validate(json::parse(doc))) out.push_back(i.rule + " " + i.path);
    return out;
  };
  using V = std::vector<std::string>;
  EXPECT_EQ(rules(R"({})"), V{"required "});
  EXPECT_EQ(rules(R"({"n": 2.5})"), V{"type /n"});
  EXPECT_EQ(rules(R"({"n": 4})"), V{"maximum /n"});
  EXPECT_EQ(rules(R"({"n": 0})"), V{"minimum /n"});
  EXPECT_EQ(rules(R"({"n": 1, "p": 0})"), V{"exclusiveMinimum /p"});
  EXPECT_EQ(rules(R"({"n": 1, "p": 10})"), V{"exclusiveMaximum /p"});
  EXPECT_EQ(rules(R"({"n": 1, "s": "aaa"})"), V{"pattern /s"});
  EXPECT_EQ(rules(R"({"n": 1, "s": "b"})"), V{"minLength /s"});
  EXPECT_EQ(rules(R"({"n": 1, "s": "bbbbb"})"), V{"maxLength /s"});
  EXPECT_EQ(rules(R"({"n": 1, "a": [1, 3, 1]})"), (V{"uniqueItems /a/2", "enum /a/1"}));
  EXPECT_EQ(rules(R"({"n": 1, "c": {"k": [2]}})"), V{"const /c"});
  EXPECT_EQ(rules(R"({"n": 1, "any": 1.5})"), V{"anyOf /any"});
  EXPECT_EQ(rules(R"({"n": 1, "one": 2})"), V{"oneOf /one"});  // matches both
  EXPECT_EQ(rules(R"({"n": 1, "no": 0})"), V{"false /no"});
  EXPECT_EQ(rules(R"({"n": 1, "extra": "x"})"), V{"type /extra"});
}

TEST(JsonSchemaTest, ShippedSchemasCompile) {
  for (DocumentKind k : {DocumentKind::kMission, DocumentKind::kSimConfig, DocumentKind::kWorld,
                         DocumentKind::kManifest}) {
    const JsonSchema s = JsonSchema::load(schemaFile(schemaDir(), k));
    EXPECT_EQ(s.root().at("properties").at("schema").at("const"), schemaName(k));
  }
}

// ------------------------------------------------------------------ mission phases

// A chain of one phase of each type about the mission's first target.
std::vector<MissionPhase> everyPhase(const std::string& target) {
  std::vector<MissionPhase> ph(4);
  ph[0].id = "find";
  ph[0].type = PhaseType::kSearch;
  ph[0].targets = {target};
  ph[1].id = "keep_behind";
  ph[1].type = PhaseType::kFollow;
  ph[1].targets = {target};
  ph[1].duration = 120.0;
  ph[1].follow.distance = 12.5;
  ph[1].follow.height_tolerance = 4.0;
  ph[1].follow.approach_s = 30.0;
  ph[2].id = "watch";
  ph[2].type = PhaseType::kTrack;
  ph[2].targets = {target};
  ph[2].duration = 60.0;
  ph[2].track.min_box_area = 900.0;
  ph[3].id = "home";
  ph[3].type = PhaseType::kAvoid;
  ph[3].avoid.goal = geometry::Vec3(10.0, -20.5, 30.0);
  ph[3].avoid.shortest_path_m = 412.25;
  ph[3].avoid.min_vertical_separation = 2.5;
  return ph;
}

TEST_F(ValidationTest, PhasesRoundTripAndValidate) {
  Mission m = scenario(ScenarioClass::kPursuit, 1).mission;
  // Without phases the document has no "phases" key (missions of every class read as before).
  EXPECT_EQ(json::parse(missionJson(m)).count("phases"), 0u);
  m.phases = everyPhase(m.objective.targets.at(0).id);
  const std::string text = missionJson(m);
  const auto issues = check(json::parse(text));
  EXPECT_TRUE(issues.empty()) << describe(issues);
  const Mission back = parseMission(text, "mission.json");
  ASSERT_EQ(back.phases.size(), 4u);
  EXPECT_EQ(back.phases[1].type, PhaseType::kFollow);
  EXPECT_EQ(back.phases[1].targets, m.phases[1].targets);
  EXPECT_EQ(*back.phases[1].duration, 120.0);
  EXPECT_EQ(back.phases[1].follow.distance, 12.5);
  EXPECT_EQ(back.phases[1].follow.height_tolerance, 4.0);
  EXPECT_EQ(back.phases[1].follow.approach_s, 30.0);
  EXPECT_EQ(back.phases[2].track.min_box_area, 900.0);
  EXPECT_FALSE(back.phases[3].duration.has_value());
  EXPECT_EQ(back.phases[3].avoid.goal, geometry::Vec3(10.0, -20.5, 30.0));
  EXPECT_EQ(back.phases[3].avoid.shortest_path_m, 412.25);
  EXPECT_EQ(back.phases[3].avoid.min_vertical_separation, 2.5);
  EXPECT_EQ(missionJson(back), text);  // byte-identical round trip
}

TEST_F(ValidationTest, PhaseRulesAreChecked) {
  Mission m = scenario(ScenarioClass::kPursuit, 1).mission;
  m.phases = everyPhase(m.objective.targets.at(0).id);
  json d = json::parse(missionJson(m));
  d["phases"][1]["targets"] = json::array({"car_nobody"});  // not an objective target
  d["phases"][2]["id"] = "find";                            // repeats phase 0's id
  d["phases"].push_back(d["phases"][0]);                    // a search after other phases
  d["phases"][4]["id"] = "again";
  auto issues = check(d);
  EXPECT_ISSUE(issues, "phase_target", "/phases/1/targets/0");
  EXPECT_ISSUE(issues, "unique_id", "/phases/2/id");
  EXPECT_ISSUE(issues, "phase_order", "/phases/4/type");
  EXPECT_EQ(issues.size(), 3u) << describe(issues);
  // The schema: a follow phase about two targets, a track fraction above 1, an avoid phase
  // without its goal.
  json s = json::parse(missionJson(m));
  s["phases"][1]["targets"].push_back(s["phases"][1]["targets"][0]);
  s["phases"][2]["criteria"]["min_tracked_fraction"] = 1.5;
  s["phases"][3].erase("goal");
  issues = check(s);
  for (const char* p : {"/phases/1", "/phases/2", "/phases/3"}) {
    bool found = false;
    for (const auto& i : issues) found = found || i.path.rfind(p, 0) == 0;
    EXPECT_TRUE(found) << "no issue at " << p << ":\n" << describe(issues);
  }
  // The reader rejects what the schema rejects, naming the field.
  auto reject = [&](const nlohmann::ordered_json& doc, const std::string& field) {
    try {
      missionFromJson(doc, "m.json");
      ADD_FAILURE() << "accepted; expected an error at " << field;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("m.json: " + field), std::string::npos) << e.what();
    }
  };
  auto r = nlohmann::ordered_json::parse(missionJson(m));
  r["phases"][3]["duration"] = 5.0;
  reject(r, "phases[3].duration");
  r = nlohmann::ordered_json::parse(missionJson(m));
  r["phases"][0]["type"] = "hover";
  reject(r, "phases[0].type");
  r = nlohmann::ordered_json::parse(missionJson(m));
  r["phases"][1]["envelope"]["distance_tolerance"] = 0.0;
  reject(r, "phases[1].envelope.distance_tolerance");
  r = nlohmann::ordered_json::parse(missionJson(m));
  r["phases"][2]["criteria"]["colour"] = "red";
  reject(r, "phases[2].criteria");
  r = nlohmann::ordered_json::parse(missionJson(m));
  r["phases"] = nlohmann::ordered_json::array();
  reject(r, "phases");
  // Negative control: the untouched document passes both.
  EXPECT_TRUE(check(json::parse(missionJson(m))).empty());
  EXPECT_NO_THROW(parseMission(missionJson(m), "m.json"));
}

}  // namespace
}  // namespace hameritt::scenario
