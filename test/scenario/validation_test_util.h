#pragma once
// Validation helpers shared by the scenario class tests: a document's issues against the
// shipped schemas and semantic rules, and their rules and paths as one string to search.

#include <gtest/gtest.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/validation.h"
#include "test_util.h"

namespace hameritt::scenario::testing {

inline std::vector<ValidationIssue> issues(const nlohmann::json& doc) {
  return validateDocument(doc, "doc.json", defaultConfigDir() + "/schema");
}

// "rule path; " for each issue.
inline std::string rules(const std::vector<ValidationIssue>& v) {
  std::string out;
  for (const auto& i : v) out += i.rule + " " + i.path + "; ";
  return out;
}

// The scenario's mission.json and sim_config.json pass the schemas and rules and read back to
// the same bytes.
inline void expectValidAndRoundTrips(const Scenario& s) {
  const std::string mj = missionJson(s.mission), sj = simConfigJson(s.sim);
  EXPECT_TRUE(issues(nlohmann::json::parse(mj)).empty())
      << rules(issues(nlohmann::json::parse(mj)));
  EXPECT_TRUE(issues(nlohmann::json::parse(sj)).empty())
      << rules(issues(nlohmann::json::parse(sj)));
  EXPECT_EQ(missionJson(parseMission(mj, "mission.json")), mj);
  EXPECT_EQ(simConfigJson(parseSimConfig(sj, "sim_config.json")), sj);
}

// The scenario of class `cls` (a class built on pursuit's scene) and `seed` comes out the same
// twice and differs with seed + 1 (the control); its first target is pursuit's of the same seed
// (id and model). Returns {that scenario, pursuit's}.
inline std::pair<Scenario, Scenario> expectDeterministicOverPursuit(ScenarioClass cls,
                                                                    std::uint64_t seed) {
  const Scenario a = generateScenario(shippedWorld(), shippedConfig(), cls, seed);
  const Scenario b = generateScenario(shippedWorld(), shippedConfig(), cls, seed);
  const Scenario c = generateScenario(shippedWorld(), shippedConfig(), cls, seed + 1);
  EXPECT_EQ(missionJson(a.mission), missionJson(b.mission));
  EXPECT_EQ(simConfigJson(a.sim), simConfigJson(b.sim));
  EXPECT_NE(missionJson(a.mission), missionJson(c.mission));  // control: the seed matters
  Scenario p = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kPursuit, seed);
  EXPECT_TRUE(p.mission.phases.empty());
  EXPECT_EQ(p.mission.objective.targets.size(), 1u);
  if (!p.mission.objective.targets.empty() && !a.mission.objective.targets.empty()) {
    EXPECT_EQ(p.mission.objective.targets[0].id, a.mission.objective.targets[0].id);
    EXPECT_EQ(p.mission.objective.targets[0].model, a.mission.objective.targets[0].model);
  }
  return {a, std::move(p)};
}

}  // namespace hameritt::scenario::testing
