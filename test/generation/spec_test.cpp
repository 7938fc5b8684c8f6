// The scenario language: every error kind with its exact message, distributions, parameters,
// imports, the compiler's narrowing and unsatisfiable specs, and the independent checker
// (with negative controls: scenes that break a requirement must be reported).

#include "hameritt/generation/spec.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>

#include "../scenario/test_util.h"
#include "hameritt/generation/batch.h"
#include "hameritt/generation/spec_sampler.h"
#include "hameritt/scenario/catalog.h"
#include "hameritt/scenario/relations.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/trajectory.h"

namespace hameritt::generation {
namespace {

using scenario::testing::messageOf;
using scenario::testing::shippedConfig;
using scenario::testing::shippedWorld;

Spec parse(const std::string& text, const std::vector<std::string>& params = {}) {
  return parseSpecText(text, "t.hspec", params, shippedWorld());
}

std::string errorOf(const std::string& text, const std::vector<std::string>& params = {}) {
  return messageOf([&] { parse(text, params); });
}

const char* kHead = "scenario area_search\n";

TEST(SpecParse, SyntaxErrorGivesLineColumnCaretAndExpectation) {
  EXPECT_EQ(errorOf(std::string(kHead) + "target car {color = red}\n"),
            "t.hspec:2:19: error: expected ':' after the attribute name, got '='\n"
            "  target car {color = red}\n"
            "                    ^");
  EXPECT_EQ(errorOf("scenario area_search\ntarget car {color: red\n"),
            "t.hspec:3:1: error: expected ',' or '}' after the attribute value, got the end of "
            "the file\n  \n  ^");
  EXPECT_EQ(errorOf("scenario area_search $\n"),
            "t.hspec:1:22: error: unexpected character '$'\n  scenario area_search $\n"
            "                       ^");
  EXPECT_EQ(errorOf("import \"never\n"),
            "t.hspec:1:8: error: unterminated string: expected '\"'\n  import \"never\n"
            "         ^");
}

TEST(SpecParse, UnknownNamesListTheNearestValidOnes) {
  EXPECT_EQ(errorOf(std::string(kHead) + "target car {color: sliver}\n"),
            "t.hspec:2:20: error: unknown color 'sliver' for target car; did you mean "
            "'silver'?; color values of car in this world: black, blue, green, grey, red, "
            "silver, white, yellow\n"
            "  target car {color: sliver}\n"
            "                     ^");
  EXPECT_NE(errorOf(std::string(kHead) + "target car {color: scarlet}\n")
                .find("t.hspec:2:20: error: unknown color 'scarlet' for target car; color values "
                      "of car in this world: black, blue, green, grey, red"),
            std::string::npos);
  const std::string op = errorOf(std::string(kHead) + "require garage RIGHTOF target\n");
  EXPECT_EQ(op.substr(0, op.find('?') + 1),
            "t.hspec:2:16: error: unknown relation operator 'RIGHTOF'; did you mean 'RIGHT_OF'?");
  const std::string stmt = errorOf(std::string(kHead) + "targte car\n");
  EXPECT_EQ(stmt.substr(0, stmt.find('?') + 1),
            "t.hspec:2:1: error: unknown statement 'targte'; did you mean 'target'?");
  const std::string key = errorOf(std::string(kHead) + "environment { snoww: 1 }\n");
  EXPECT_EQ(key.substr(0, key.find('\n')),
            "t.hspec:2:15: error: unknown setting 'snoww' in environment; did you mean 'snow'?; "
            "settings of environment: dust, fog, foliage, gusts, rain, snow, time, wind");
  const std::string attr =
      errorOf(std::string(kHead) + "require garage RIGHT_OF target {door: 1}\n");
  EXPECT_EQ(attr.substr(0, attr.find('\n')),
            "t.hspec:2:33: error: unknown attribute 'door' of garage; did you mean 'doors'?; "
            "attributes of garage in this world: color, doors");
  const std::string cls = errorOf("scenario area_serch\n");
  EXPECT_EQ(cls.substr(0, cls.find('\n')),
            "t.hspec:1:10: error: unknown mission class 'area_serch'; did you mean "
            "'area_search'?; classes: area_search, route_search, pursuit");
  // avoid is a mission class but not one a spec can describe.
  const std::string avoid = errorOf("scenario avoid\n");
  EXPECT_EQ(avoid.substr(0, avoid.find(';')), "t.hspec:1:10: error: unknown mission class 'avoid'");
}

TEST(SpecParse, TypeErrors) {
  const std::string range = errorOf(std::string(kHead) + "environment { snow: 1.5 }\n");
  EXPECT_EQ(range.substr(0, range.find('\n')),
            "t.hspec:2:21: error: environment.snow: expected values within [0, 1], got 1.5");
  const std::string whole = errorOf(std::string(kHead) + "confusers { count: 1.5 }\n");
  EXPECT_EQ(whole.substr(0, whole.find('\n')),
            "t.hspec:2:20: error: confusers.count: expected a whole number or a range of whole "
            "numbers, got 1.5");
  const std::string op = errorOf(std::string(kHead) + "require fence RIGHT_OF target\n");
  EXPECT_EQ(op.substr(0, op.find('\n')),
            "t.hspec:2:9: error: RIGHT_OF does not apply to a fence; it relates: house, garage, "
            "tree, car, pedestrian");
  const std::string prob = errorOf(std::string(kHead) + "prefer 1.5 tree NEXT_TO target\n");
  EXPECT_EQ(prob.substr(0, prob.find('\n')),
            "t.hspec:2:8: error: expected a probability strictly between 0 and 1, got 1.5");
  const std::string name = errorOf(std::string(kHead) + "environment { time: dusky }\n");
  EXPECT_EQ(name.substr(0, name.find('\n')),
            "t.hspec:2:21: error: unknown name 'dusky'; did you mean 'dusk'?; periods of the "
            "day: dawn, day, dusk, night");
  EXPECT_EQ(messageOf([] { parse("target car\n"); }),
            "t.hspec:1:1: error: missing 'scenario' statement: expected 'scenario area_search', "
            "'scenario route_search' or 'scenario pursuit'");
  const std::string moving = errorOf("scenario area_search\ntarget car moving\n");
  EXPECT_EQ(moving.substr(0, moving.find('\n')),
            "t.hspec:2:1: error: an area_search target is parked; expected 'parked'");
  const std::string ev = errorOf(std::string(kHead) + "require tree EVENTUALLY_NEXT_TO target\n");
  EXPECT_EQ(ev.substr(0, ev.find('\n')),
            "t.hspec:2:1: error: EVENTUALLY_* applies to a moving target (route_search, "
            "pursuit); an area_search target is parked: drop EVENTUALLY_");
}

TEST(SpecParse, DistributionsDrawInsideTheirSupport) {
  const Spec s = parse(std::string(kHead) +
                       "environment { time: dusk, snow: normal(0.5, 0.2, 0.3, 0.6), "
                       "fog: choice(0: 3, 0.5: 1) }\nconfusers { count: 2..4 }\n");
  const Distribution* time = s.setting("environment.time");
  const Distribution* snow = s.setting("environment.snow");
  const Distribution* fog = s.setting("environment.fog");
  const Distribution* count = s.setting("confusers.count");
  ASSERT_TRUE(time && snow && fog && count);
  EXPECT_EQ(time->text(), "range(17.5, 19.5)");
  EXPECT_EQ(snow->text(), "normal(0.5, 0.2, 0.3, 0.6)");
  EXPECT_EQ(fog->text(), "choice(0: 3, 0.5: 1)");
  EXPECT_EQ(count->text(), "2..4");
  int fog_half = 0, counts[5] = {0, 0, 0, 0, 0};
  double snow_sum = 0;
  constexpr int kN = 4000;
  scenario::Rng rng(7);
  for (int i = 0; i < kN; ++i) {
    const double t = time->draw(rng.unit()), sn = snow->draw(rng.unit());
    EXPECT_TRUE(t >= 17.5 && t <= 19.5);
    EXPECT_TRUE(sn >= 0.3 && sn <= 0.6);
    snow_sum += sn;
    fog_half += fog->draw(rng.unit()) == 0.5;
    const double c = count->draw(rng.unit());
    ASSERT_TRUE(c == 2 || c == 3 || c == 4) << c;
    ++counts[static_cast<int>(c)];
  }
  // Weighted choice: P(0.5) = 1/4, within 3 sigma.
  EXPECT_NEAR(fog_half, kN / 4.0, 3 * std::sqrt(kN * 0.25 * 0.75));
  for (int c = 2; c <= 4; ++c) EXPECT_NEAR(counts[c], kN / 3.0, 3 * std::sqrt(kN * 2.0 / 9));
  // Truncated normal N(0.5, 0.2) on [0.3, 0.6]: its mean is below 0.5 (more mass left of it).
  EXPECT_LT(snow_sum / kN, 0.5);
  EXPECT_GT(snow_sum / kN, 0.4);
  EXPECT_FALSE(time->contains(19.6));
  EXPECT_TRUE(fog->contains(0.5));
  EXPECT_FALSE(fog->contains(0.25));  // negative control: between the choices
}

TEST(SpecParse, ParamsAndOverrides) {
  const std::string text = std::string(kHead) + "param snow = 0.2\nenvironment { snow: snow }\n";
  EXPECT_EQ(parse(text).setting("environment.snow")->text(), "0.2");
  EXPECT_EQ(parse(text, {"snow=0.8"}).setting("environment.snow")->text(), "0.8");
  EXPECT_EQ(parse(text, {"snow=range(0.1, 0.3)"}).setting("environment.snow")->text(),
            "range(0.1, 0.3)");
  EXPECT_NE(parse(text).hash, parse(text, {"snow=0.8"}).hash);
  EXPECT_EQ(errorOf(text, {"snwo=0.8"}),
            "--param: unknown parameter 'snwo'; did you mean 'snow'?; parameters of this spec: "
            "snow");
  EXPECT_EQ(errorOf(text, {"snow=0.8", "snow=0.9"}),
            "--param: parameter 'snow' given more than once");
  EXPECT_EQ(errorOf(text, {"snow"}), "--param: expected NAME=VALUE, got 'snow'");
  const std::string bad = errorOf(text, {"snow=1.5"});
  EXPECT_EQ(bad.substr(0, bad.find('\n')),
            "t.hspec:3:21: error: environment.snow: expected values within [0, 1], got 1.5 (from "
            "param 'snow')");
}

TEST(SpecParse, ImportsComposeAndOverride) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("spec_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir / "base.hspec")
        << "param snow = 0.5\nenvironment { time: dusk, snow: snow }\n"
           "require garage NEXT_TO target\n";
    std::ofstream(dir / "top.hspec")
        << "import \"base.hspec\"\nscenario area_search\n"
           "environment { time: 12 }\nrequire not tree NEXT_TO target\n";
    std::ofstream(dir / "loop.hspec") << "import \"loop.hspec\"\n";
  }
  const Spec s = parseSpec((dir / "top.hspec").string(), {"snow=0.7"}, shippedWorld());
  EXPECT_EQ(s.setting("environment.time")->text(), "12");   // overridden by the importer
  EXPECT_EQ(s.setting("environment.snow")->text(), "0.7");  // the import's param, overridden
  ASSERT_EQ(s.requirements.size(), 2u);
  EXPECT_EQ(s.requirements[0].text, "garage NEXT_TO target");
  EXPECT_EQ(s.requirements[1].text, "not tree NEXT_TO target");
  const std::string loop =
      messageOf([&] { parseSpec((dir / "loop.hspec").string(), {}, shippedWorld()); });
  EXPECT_NE(loop.find("loop.hspec:1:8: error: import cycle"), std::string::npos) << loop;
  std::filesystem::remove_all(dir);
}

TEST(SpecCompile, UnsatisfiableNamesTheRequirementAndTheNarrowing) {
  const Spec s = parse(std::string(kHead) +
                       "target car {vehicle_class: sedan, color: red} parked\n"
                       "require street ON_TOP_OF target\nrequire driveway ON_TOP_OF target\n");
  const std::string m = messageOf([&] { CompiledSpec(s, shippedWorld(), shippedConfig()); });
  const std::regex re(
      "t\\.hspec:4:1: error: unsatisfiable in this world: driveway ON_TOP_OF target: 0 of "
      "([0-9]+) candidates \\(parking places x looks: ([0-9]+) -> vehicle_class sedan: ([0-9]+) "
      "-> color red: ([0-9]+) -> street ON_TOP_OF target: ([0-9]+)\\)");
  std::smatch mm;
  ASSERT_TRUE(std::regex_match(m, mm, re)) << m;
  // "0 of N": N is what the previous requirement left; each step narrows.
  EXPECT_EQ(mm[1], mm[5]);
  const long all = std::stol(mm[2]), sedan = std::stol(mm[3]), red = std::stol(mm[4]);
  EXPECT_EQ(sedan * 10, all * 3);  // 3 of the 10 catalog models are sedans
  EXPECT_EQ(red * 8, sedan);       // 1 of 8 colours
  EXPECT_GT(std::stol(mm[5]), 0);
  EXPECT_LT(std::stol(mm[5]), red);
}

TEST(SpecCompile, SoftRequirementsHoldWithTheirProbability) {
  const Spec s = parse(std::string(kHead) + "target car parked\nprefer 0.3 tree NEXT_TO target\n");
  const CompiledSpec c(s, shippedWorld(), shippedConfig());
  constexpr int kN = 3000;
  int held = 0;
  for (int i = 0; i < kN; ++i) {
    const ScenarioDraw d = c.draw(scenario::batchSeed(5, i), i, 5, SamplerKind::kRandom);
    ASSERT_TRUE(d.plan.provenance);
    const auto& v = d.plan.provenance->values.back();
    ASSERT_EQ(v.first, "prefer tree NEXT_TO target");
    held += std::get<bool>(v.second);
  }
  EXPECT_NEAR(held, 0.3 * kN, 3 * std::sqrt(kN * 0.3 * 0.7));
}

TEST(SpecCompile, HaltonCoversARangeEvenly) {
  const Spec s = parse(std::string(kHead) + "environment { fog: range(0, 1) }\n");
  const CompiledSpec c(s, shippedWorld(), shippedConfig());
  int bins[10] = {0};
  for (int i = 0; i < 200; ++i) {
    const ScenarioDraw d = c.draw(scenario::batchSeed(3, i), i, 3, SamplerKind::kHalton);
    const double fog = std::get<double>(d.plan.provenance->values.front().second);
    ++bins[std::min(9, static_cast<int>(fog * 10))];
  }
  // Low discrepancy: every tenth of the range gets 20 +- 1 points (random: +- 13 at 3 sigma).
  for (int b : bins) EXPECT_NEAR(b, 20, 1);
}

TEST(SpecCheck, GeneratedScenarioMeetsTheSpecAndBrokenOnesAreReported) {
  const Spec s = parse(std::string(kHead) +
                       "target car {vehicle_class: sedan, color: red} parked\n"
                       "require garage RIGHT_OF target\nenvironment { snow: 0.6 }\n");
  scenario::GeneratorConfig cfg = shippedConfig();
  cfg.perception_paths = false;
  const CompiledSpec c(s, shippedWorld(), cfg);
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const ScenarioDraw d = c.draw(seed, seed, 1, SamplerKind::kRandom);
    const scenario::Scenario sc =
        scenario::generateScenario(shippedWorld(), d.config, s.cls, seed, &d.plan);
    const auto ok = checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, sc.sim, nullptr);
    EXPECT_TRUE(ok.empty()) << seed << ": " << ok.front();
    ASSERT_TRUE(sc.sim.spec);
    EXPECT_EQ(sc.sim.environment.snow, 0.6);
    // Negative controls: a blue target, a target moved away from its garage, other snow.
    scenario::SimConfig blue = sc.sim;
    for (auto& se : blue.entities) {
      if (se.role == "target") se.entity.attributes.set("color", std::string("blue"));
    }
    const auto f1 = checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, blue, nullptr);
    ASSERT_EQ(f1.size(), 1u);
    EXPECT_NE(f1[0].find("color 'blue' is not one of red"), std::string::npos) << f1[0];
    scenario::SimConfig moved = sc.sim;
    for (auto& se : moved.entities) {
      if (se.role == "target")
        se.entity.box.yaw = geometry::wrapPi(se.entity.box.yaw + geometry::kPi);
    }
    const auto f2 = checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, moved, nullptr);
    ASSERT_FALSE(f2.empty());
    EXPECT_NE(f2[0].find("requirement 'garage RIGHT_OF target' does not hold"), std::string::npos)
        << f2[0];
    scenario::SimConfig snow = sc.sim;
    snow.environment.snow = 0.2;
    const auto f3 = checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, snow, nullptr);
    ASSERT_EQ(f3.size(), 1u);
    EXPECT_EQ(f3[0], "environment.snow: 0.2 is outside 0.6");
  }
}

TEST(SpecCheck, SameSpecAndSeedGiveTheSameScenario) {
  const Spec s = parse(std::string(kHead) +
                       "target car {color: red} parked\n"
                       "require garage RIGHT_OF target\nenvironment { fog: range(0, 1) }\n");
  scenario::GeneratorConfig cfg = shippedConfig();
  cfg.perception_paths = false;
  const CompiledSpec c(s, shippedWorld(), cfg);
  auto json = [&](std::uint64_t seed) {
    const ScenarioDraw d = c.draw(seed, 0, 9, SamplerKind::kRandom);
    const auto sc = scenario::generateScenario(shippedWorld(), d.config, s.cls, seed, &d.plan);
    return scenario::missionJson(sc.mission) + scenario::simConfigJson(sc.sim);
  };
  EXPECT_EQ(json(11), json(11));
  EXPECT_NE(json(11), json(12));
}

// The compiler's pruned relation evaluation agrees with the checker's reference on every
// parking place x model of the shipped world, for every relation requirement of the examples.
TEST(SpecCompile, PrunedRelationsAgreeWithTheReference) {
  const auto& world = shippedWorld();
  const scenario::RelationEvaluator eval(world, shippedConfig().relations);
  const auto& models = scenario::catalog::carModels();
  const std::string dir = scenario::defaultConfigDir() + "/../scenarios/specs";
  long compared = 0, held = 0, differ = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() != ".hspec") continue;
    const std::string w = specWorld(e.path().string());
    if (!w.empty() && w != "suburb") continue;  // written for another world
    const Spec s = parseSpec(e.path().string(), {}, world);
    for (const auto& r : s.requirements) {
      if (r.eventually) continue;
      Requirement flipped = r;  // the negative control: another operator
      flipped.op = r.op == scenario::RelationOp::kRightOf ? scenario::RelationOp::kLeftOf
                                                          : scenario::RelationOp::kRightOf;
      for (std::size_t i = 0; i < world.slots().size(); i += 3) {
        const auto& sl = world.slots()[i];
        for (const auto& m : models) {
          const geometry::OrientedBox box =
              scenario::boxFromPose(geometry::Vec3(scenario::roundMilli(sl.position.x()),
                                                   scenario::roundMilli(sl.position.y()),
                                                   scenario::roundMilli(sl.ground_z)),
                                    scenario::roundMilli(geometry::wrapPi(sl.yaw)),
                                    geometry::Vec3(m.length, m.width, m.height));
          const bool fast = worldRelationHolds(eval, world, r, box, true);
          ASSERT_EQ(fast, worldRelationHolds(eval, world, r, box, false))
              << e.path() << ": " << r.text << " at slot " << i << ", " << m.model;
          ++compared;
          held += fast;
          differ += fast != worldRelationHolds(eval, world, flipped, box, false);
        }
      }
    }
  }
  EXPECT_GT(compared, 20000);
  EXPECT_GT(held, 1000);
  EXPECT_GT(differ, 100);  // the comparison can fail: another operator gives other answers
}

TEST(SpecCompile, AoiOffsetAndUavStartAreMetAndChecked) {
  const Spec s = parse(std::string(kHead) +
                       "target car parked\naois { count: 1, target_offset: range(5, 30) }\n"
                       "uav { start_within: range(200, 250) }\n");
  scenario::GeneratorConfig cfg = shippedConfig();
  cfg.perception_paths = false;
  const CompiledSpec c(s, shippedWorld(), cfg);
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const ScenarioDraw d = c.draw(seed, seed, 1, SamplerKind::kRandom);
    const scenario::Scenario sc =
        scenario::generateScenario(shippedWorld(), d.config, s.cls, seed, &d.plan);
    const auto ok = checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, sc.sim, nullptr);
    EXPECT_TRUE(ok.empty()) << seed << ": " << ok.front();
    // Negative controls: the UAV 400 m from the target; the AOI moved 12 m.
    scenario::SimConfig far = sc.sim;
    for (const auto& se : sc.sim.entities) {
      if (se.role == "target") {
        far.uav.start.x = se.entity.box.center2().x() + 400.0;
        far.uav.start.y = se.entity.box.center2().y();
      }
    }
    const auto f1 = checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, far, nullptr);
    ASSERT_EQ(f1.size(), 1u);
    EXPECT_NE(f1[0].find("uav.start_within: the UAV starts"), std::string::npos) << f1[0];
    scenario::Mission moved = sc.mission;
    std::vector<geometry::Vec2> v = moved.aois.front().polygon.vertices();
    for (auto& p : v) p += geometry::Vec2(0.0, 12.0);
    moved.aois.front().polygon = geometry::Polygon(v);
    const auto f2 = checkScenarioAgainstSpec(s, shippedWorld(), cfg, moved, sc.sim, nullptr);
    ASSERT_FALSE(f2.empty()) << seed;
    EXPECT_NE(f2[0].find("aois.target_offset"), std::string::npos) << f2[0];
  }
  // Refused at compile time: an offset that can put the target outside its AOI, and an offset
  // in a pursuit.
  EXPECT_NE(messageOf([&] {
              CompiledSpec(parse(std::string(kHead) + "aois { target_offset: 100 }\n"),
                           shippedWorld(), cfg);
            }).find("aois.target_offset: up to 100 m"),
            std::string::npos);
  EXPECT_NE(errorOf("scenario pursuit\ntarget car\naois { target_offset: 10 }\n")
                .find("aois.target_offset applies to area_search only"),
            std::string::npos);
}

// Generates `n` scenarios of a spec and checks each with the independent checker.
std::vector<scenario::Scenario> generateChecked(const Spec& s, int n) {
  scenario::GeneratorConfig cfg = shippedConfig();
  cfg.perception_paths = false;
  const CompiledSpec c(s, shippedWorld(), cfg);
  std::vector<scenario::Scenario> out;
  for (int i = 0; i < n; ++i) {
    const std::uint64_t seed = scenario::batchSeed(21, static_cast<std::uint64_t>(i));
    const ScenarioDraw d = c.draw(seed, static_cast<std::uint64_t>(i), 21, SamplerKind::kRandom);
    out.push_back(scenario::generateScenario(shippedWorld(), d.config, s.cls, seed, &d.plan));
    const auto fails = checkScenarioAgainstSpec(s, shippedWorld(), cfg, out.back().mission,
                                                out.back().sim, nullptr);
    EXPECT_TRUE(fails.empty()) << i << ": " << fails.front();
  }
  return out;
}

std::vector<std::string> checkOf(const Spec& s, const scenario::Scenario& sc,
                                 const scenario::SimConfig& sim) {
  scenario::GeneratorConfig cfg = shippedConfig();
  cfg.perception_paths = false;
  return checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, sim, nullptr);
}

// The scene without the entity `id` (a negative control's doctored scene).
scenario::SimConfig withoutEntity(const scenario::SimConfig& sim, const std::string& id) {
  scenario::SimConfig out = sim;
  out.entities.erase(std::remove_if(out.entities.begin(), out.entities.end(),
                                    [&](const auto& se) { return se.entity.id == id; }),
                     out.entities.end());
  return out;
}

TEST(SpecRelated, ACarOrPedestrianIsPlacedBesideTheTargetAndChecked) {
  struct Case {
    std::string text, related, role;
  };
  const Case cases[] = {
      {"target car parked\nrequire car NEXT_TO target {color: white}\n",
       "car NEXT_TO target {color: white}", "traffic"},
      {"target car {vehicle_class: sedan} parked\nrequire garage RIGHT_OF target\n"
       "require car IN_FRONT_OF target {vehicle_class: van | pickup}\n",
       "car IN_FRONT_OF target {vehicle_class: van | pickup}", "traffic"},
      {"target car parked\nrequire pedestrian NEXT_TO target {clothing_color: red}\n",
       "pedestrian NEXT_TO target {clothing_color: red}", "pedestrian"},
  };
  int placed = 0;
  for (const auto& k : cases) {
    const Spec s = parse(std::string(kHead) + k.text);
    for (const auto& sc : generateChecked(s, 12)) {
      // The relation is listed, with a parked car or standing pedestrian of the scenario.
      const scenario::ScenarioEntity* rel = nullptr;
      for (const auto& r : sc.mission.relations) {
        for (const auto& se : sc.sim.entities) {
          if (se.entity.id == r.related_id && se.role == k.role && se.trajectory.empty() &&
              r.related_class == scenario::toString(se.entity.cls))
            rel = &se;
        }
      }
      if (!rel) continue;  // a world entity meets it
      ++placed;
      if (k.role == "pedestrian") {
        EXPECT_EQ(rel->entity.attributes.str("activity"), "standing");
      }
      // Negative control: without the placed entity the requirement fails.
      const auto f = checkOf(s, sc, withoutEntity(sc.sim, rel->entity.id));
      ASSERT_FALSE(f.empty()) << k.text;
      EXPECT_NE(f[0].find("requirement '" + k.related + "' does not hold"), std::string::npos)
          << f[0];
    }
  }
  EXPECT_GE(placed, 30);  // of 36: world cars rarely meet them
}

TEST(SpecRelated, NegationsKeepCarsAwayAndAreChecked) {
  const Spec s = parse(std::string(kHead) +
                       "target car parked\nrequire car LEFT_OF target\n"
                       "require not car NEXT_TO target\nrequire not pedestrian NEXT_TO target\n");
  for (const auto& sc : generateChecked(s, 10)) {
    // Negative control: a standing pedestrian put beside the target breaks the negation.
    const scenario::ScenarioEntity* target = nullptr;
    for (const auto& se : sc.sim.entities) {
      if (se.role == "target") target = &se;
    }
    ASSERT_TRUE(target);
    scenario::ScenarioEntity p;
    p.entity.id = "pedestrian_99";
    p.entity.cls = scenario::EntityClass::kPedestrian;
    p.role = "pedestrian";
    const geometry::OrientedBox& tb = target->entity.box;
    const geometry::Vec2 side(-std::sin(tb.yaw), std::cos(tb.yaw));
    const geometry::Vec2 at = tb.center2() - (0.5 * tb.size.y() + 1.0) * side;
    p.entity.box = scenario::boxFromPose(geometry::Vec3(at.x(), at.y(), tb.minZ()), tb.yaw,
                                         geometry::Vec3(0.5, 0.6, 1.75));
    scenario::SimConfig near = sc.sim;
    near.entities.push_back(p);
    const auto f = checkOf(s, sc, near);
    ASSERT_EQ(f.size(), 1u);
    EXPECT_EQ(f[0].find("requirement 'not pedestrian NEXT_TO target' does not hold"), 0u) << f[0];
  }
}

// Two placing relations in one spec: each scene gets a white car next to the target and a
// pedestrian on its left (or the scene already meets one of them), both checked from the scene;
// without the pedestrian placed for the second relation the check fails (negative control).
TEST(SpecRelated, TwoPlacedEntitiesEachHoldAndAreChecked) {
  const Spec s = parse(std::string(kHead) +
                       "target car parked\nrequire car NEXT_TO target {color: white}\n"
                       "require pedestrian LEFT_OF target\nrequire not car IN_FRONT_OF target\n");
  int both = 0, removed = 0;
  for (const auto& sc : generateChecked(s, 24)) {
    const scenario::ScenarioEntity* car = nullptr;
    const scenario::ScenarioEntity* ped = nullptr;
    for (const auto& r : sc.mission.relations) {
      for (const auto& se : sc.sim.entities) {
        if (se.entity.id != r.related_id || !se.trajectory.empty()) continue;
        if (r.op == scenario::RelationOp::kNextTo && se.role == "traffic" &&
            se.entity.attributes.str("color") == "white")
          car = &se;
        if (r.op == scenario::RelationOp::kLeftOf && se.role == "pedestrian") ped = &se;
      }
    }
    if (!car || !ped) continue;  // a world entity meets one of them
    ++both;
    EXPECT_EQ(ped->entity.attributes.str("activity"), "standing");
    EXPECT_GE(geometry::footprintDistance(car->entity.box, ped->entity.box), 0.3);
    const auto f = checkOf(s, sc, withoutEntity(sc.sim, ped->entity.id));
    ASSERT_FALSE(f.empty());
    EXPECT_EQ(f[0], "requirement 'pedestrian LEFT_OF target' does not hold for target " +
                        sc.mission.objective.targets.front().id + " (recomputed from the scene)");
    ++removed;
  }
  EXPECT_GE(both, 18);  // of 24: world entities rarely meet either
  EXPECT_EQ(removed, both);
}

// Placing relations that each can be met but not together are refused at compile time, naming
// the later one; a soft second one holds with its probability.
TEST(SpecRelated, PlacedPairsUnsatisfiableTogetherAreRefusedAndSoftOnesHoldAtRate) {
  scenario::GeneratorConfig cfg = shippedConfig();
  cfg.perception_paths = false;
  // Each alone compiles; together they need two cars next to the target, and with none in
  // front of it only the place behind it is left.
  const std::string one = "target car parked\nrequire not car IN_FRONT_OF target\n";
  EXPECT_NO_THROW(
      CompiledSpec(parse(std::string(kHead) + one + "require car NEXT_TO target {color: white}\n"),
                   shippedWorld(), cfg));
  EXPECT_NO_THROW(
      CompiledSpec(parse(std::string(kHead) + one + "require car NEXT_TO target {color: black}\n"),
                   shippedWorld(), cfg));
  const std::string pair = messageOf([&] {
    CompiledSpec(parse(std::string(kHead) + one +
                       "require car NEXT_TO target {color: white}\n"
                       "require car NEXT_TO target {color: black}\n"),
                 shippedWorld(), cfg);
  });
  EXPECT_EQ(pair.find("t.hspec:5:1: error: unsatisfiable in this world: car NEXT_TO target "
                      "{color: black}: 0 of "),
            0u)
      << pair;
  const Spec soft = parse(std::string(kHead) +
                          "target car parked\nrequire car NEXT_TO target {color: white}\n"
                          "prefer 0.3 pedestrian RIGHT_OF target\n");
  constexpr int kN = 120;
  int held = 0;
  for (const auto& sc : generateChecked(soft, kN)) {
    std::vector<RequirementCheck> checks;
    EXPECT_TRUE(
        checkScenarioAgainstSpec(soft, shippedWorld(), cfg, sc.mission, sc.sim, &checks).empty());
    ASSERT_EQ(checks.size(), 1u);
    held += checks[0].holds;
  }
  EXPECT_LE(std::abs(held - kN * 0.3), 3 * std::sqrt(kN * 0.3 * 0.7)) << held;
  EXPECT_GT(std::abs(held - kN * 0.7), 3 * std::sqrt(kN * 0.3 * 0.7)) << held;  // control
}

// Whether `held` of `n` is within 3 sigma of n * p.
bool withinThreeSigma(int held, int n, double p) {
  return std::abs(held - n * p) <= 3 * std::sqrt(n * p * (1 - p));
}

TEST(SpecRelated, APreferredPlacedEntityHoldsWithItsProbability) {
  const Spec s = parse(std::string(kHead) +
                       "target car parked\nprefer 0.4 car NEXT_TO target {vehicle_class: van}\n"
                       "require not pedestrian NEXT_TO target\n");
  constexpr int kN = 200;
  scenario::GeneratorConfig cfg = shippedConfig();
  cfg.perception_paths = false;
  int held = 0, placed = 0, removed = 0;
  for (const auto& sc : generateChecked(s, kN)) {
    std::vector<RequirementCheck> soft;
    EXPECT_TRUE(
        checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, sc.sim, &soft).empty());
    ASSERT_EQ(soft.size(), 1u);
    EXPECT_EQ(soft[0].requirement, "car NEXT_TO target {vehicle_class: van}");
    held += soft[0].holds;
    // The van placed for it (a parked traffic car): without it the scene no longer agrees with
    // the outcome drawn (negative control).
    for (const auto& se : sc.sim.entities) {
      if (se.role != "traffic" || !se.trajectory.empty() ||
          se.entity.attributes.str("vehicle_class") != "van")
        continue;
      ++placed;
      EXPECT_TRUE(soft[0].holds);
      if (removed >= 5) break;
      scenario::SimConfig without = sc.sim;
      const std::string id = se.entity.id;
      without.entities.erase(std::remove_if(without.entities.begin(), without.entities.end(),
                                            [&](const auto& e) { return e.entity.id == id; }),
                             without.entities.end());
      const auto f = checkOf(s, sc, without);
      ASSERT_EQ(f.size(), 1u);
      EXPECT_EQ(f[0],
                "soft requirement 'car NEXT_TO target {vehicle_class: van}' was drawn to hold but "
                "does not hold in the scene");
      ++removed;
      break;
    }
  }
  EXPECT_TRUE(withinThreeSigma(held, kN, 0.4)) << held << " of " << kN;
  // Negative controls: the same count is far outside 3 sigma of 0.8 and of 0.1.
  EXPECT_FALSE(withinThreeSigma(held, kN, 0.8)) << held;
  EXPECT_FALSE(withinThreeSigma(held, kN, 0.1)) << held;
  // Most scenes drawn to hold get their van constructed (the world's own cars rarely meet it).
  EXPECT_GE(placed, held * 3 / 4);
  EXPECT_LE(placed, held);
  EXPECT_EQ(removed, 5);
}

// The batch's per-scenario check (hameritt_generate --verify): every scenario passes the
// checker of its own spec; checked against another spec (a blue target), the batch fails and
// leaves no scenario behind (negative control).
TEST(SpecVerify, EveryScenarioIsCheckedBeforeItIsWritten) {
  const Spec red = parse(std::string(kHead) +
                         "target car {color: red} parked\nrequire garage RIGHT_OF target\n");
  const Spec blue = parse(std::string(kHead) + "target car {color: blue} parked\n");
  scenario::GeneratorConfig cfg = shippedConfig();
  cfg.perception_paths = false;
  const CompiledSpec c(red, shippedWorld(), cfg);
  const std::string out = ::testing::TempDir() + "/spec_verify_" + std::to_string(::getpid());
  scenario::BatchRequest req;
  req.spec = &c;
  req.count = 6;
  req.seed = 4;
  req.jobs = 2;
  req.out_dir = out;
  std::atomic<int> checked{0};
  const Spec* against = &red;
  req.check = [&](const scenario::Scenario& s) {
    const auto f =
        checkScenarioAgainstSpec(*against, shippedWorld(), cfg, s.mission, s.sim, nullptr);
    if (!f.empty()) throw scenario::GenerationError(f.front());
    ++checked;
  };
  EXPECT_EQ(scenario::generateBatch(shippedWorld(), cfg, req).size(), 6u);
  EXPECT_EQ(checked.load(), 6);
  std::filesystem::remove_all(out);
  against = &blue;
  checked = 0;
  std::string what = "(no error)";
  try {
    scenario::generateBatch(shippedWorld(), cfg, req);
  } catch (const scenario::GenerationError& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("color 'red' is not one of blue"), std::string::npos) << what;
  EXPECT_EQ(checked.load(), 0);
  int left = 0;
  for (const auto& e : std::filesystem::directory_iterator(out)) left += e.is_directory();
  EXPECT_EQ(left, 0);
  std::filesystem::remove_all(out);
}

TEST(SpecRelated, TypeCheckerRules) {
  // 'prefer' on a placed entity is accepted (constructed in the scenarios drawn to meet it).
  EXPECT_NO_THROW(parse(std::string(kHead) + "target car parked\nprefer 0.5 car NEXT_TO target\n"));
  // Several placing relations: one entity each, in the order written.
  EXPECT_NO_THROW(parse(std::string(kHead) +
                        "target car parked\nrequire car NEXT_TO target\n"
                        "require pedestrian LEFT_OF target\nprefer 0.5 car RIGHT_OF target\n"));
  const std::string four = errorOf(std::string(kHead) +
                                   "target car parked\nrequire car NEXT_TO target\n"
                                   "require pedestrian LEFT_OF target\nprefer 0.5 car RIGHT_OF "
                                   "target\nrequire pedestrian IN_FRONT_OF target\n");
  EXPECT_EQ(four.substr(0, four.find('\n')),
            "t.hspec:6:1: error: at most 3 requirements per spec place a car or pedestrian beside "
            "the target; this is one more");
  const std::string walk = errorOf(std::string(kHead) +
                                   "target car parked\n"
                                   "require pedestrian NEXT_TO target {activity: walking}\n");
  EXPECT_EQ(walk.substr(0, walk.find('\n')),
            "t.hspec:3:36: error: the pedestrian placed for a relation to the parked target "
            "stands: activity must allow 'standing'");
  // Negations add up with the one placing relation.
  EXPECT_NO_THROW(parse(std::string(kHead) +
                        "target car parked\nrequire car NEXT_TO target\n"
                        "require not car IN_FRONT_OF target\nrequire not pedestrian NEXT_TO "
                        "target\n"));
}

// The shipped generator configuration without perception paths (not checked by a spec).
scenario::GeneratorConfig specConfig() {
  scenario::GeneratorConfig c = shippedConfig();
  c.perception_paths = false;
  return c;
}

// Scenario `seed` of a compiled spec, as hameritt_generate --spec makes it, and the checker's
// verdict on it (empty: every requirement holds).
struct SpecScene {
  scenario::Scenario sc;
  std::vector<std::string> fails;
};
SpecScene specScene(const Spec& s, const CompiledSpec& c, const scenario::GeneratorConfig& cfg,
                    std::uint64_t seed) {
  const ScenarioDraw d = c.draw(seed, seed, 1, SamplerKind::kRandom);
  SpecScene out{scenario::generateScenario(shippedWorld(), d.config, s.cls, seed, &d.plan), {}};
  out.fails = checkScenarioAgainstSpec(s, shippedWorld(), cfg, out.sc.mission, out.sc.sim, nullptr);
  return out;
}

// Relations of a moving target: at t = 0 (where a route-search car starts), and EVENTUALLY_* at
// a later sample of its trajectory with an entity not so related at t = 0.
const char* kRoute =
    "scenario route_search\ntarget car {vehicle_class: sedan} moving\n"
    "require house LEFT_OF target\nrequire garage EVENTUALLY_RIGHT_OF target\n";

TEST(SpecMoving, TypeCheckerRules) {
  auto first = [](const std::string& e) { return e.substr(0, e.find('\n')); };
  const char* kRouteHead = "scenario route_search\ntarget car moving\n";
  EXPECT_EQ(first(errorOf(std::string(kRouteHead) + "require car LEFT_OF target\n")),
            "t.hspec:3:1: error: a route_search target relates to the neighborhood (street, "
            "house, building, ...): relations to cars and pedestrians apply to parked targets");
  EXPECT_EQ(first(errorOf("scenario pursuit\ntarget car\nrequire car EVENTUALLY_NEXT_TO target\n")),
            "t.hspec:3:1: error: EVENTUALLY_* relates a moving target to the neighborhood "
            "(street, house, building, ...), or a pursuit target to its running pedestrians "
            "('pedestrian EVENTUALLY_NEXT_TO target')");
  const std::string expect_require =
      "EVENTUALLY_* is constructed where the target drives: expected 'require' without 'not' (a "
      "negation or a 'prefer' would have to hold over the whole drive)";
  EXPECT_EQ(
      first(errorOf(std::string(kRouteHead) + "require not house EVENTUALLY_LEFT_OF target\n")),
      "t.hspec:3:1: error: " + expect_require);
  EXPECT_EQ(
      first(errorOf(std::string(kRouteHead) + "prefer 0.4 house EVENTUALLY_LEFT_OF target\n")),
      "t.hspec:3:1: error: " + expect_require);
  // Accepted: every operator in its EVENTUALLY_ form on the neighborhood, static ones too.
  EXPECT_NO_THROW(parse(std::string(kRouteHead) +
                        "require street ON_TOP_OF target\nrequire not tree NEXT_TO target\n"
                        "require house EVENTUALLY_IN_FRONT_OF target\n"
                        "require garage EVENTUALLY_ORTHOGONAL_TO target\n"
                        "require driveway EVENTUALLY_NOT_ON_TOP_OF target\n"));
}

TEST(SpecMoving, RouteSearchRelationsAreMetAndChecked) {
  const Spec s = parse(kRoute);
  const scenario::GeneratorConfig cfg = specConfig();
  const CompiledSpec c(s, shippedWorld(), cfg);
  ASSERT_EQ(c.steps().size(), 4u);
  EXPECT_EQ(c.steps()[0].label, "route starts x looks");
  EXPECT_EQ(c.steps()[1].label, "vehicle_class sedan");
  EXPECT_EQ(c.steps()[2].label, "house LEFT_OF target");
  EXPECT_EQ(c.steps()[3].label, "garage EVENTUALLY_RIGHT_OF target");
  // Each requirement narrows the set, and the last count is the feasible set (x colours).
  EXPECT_LT(c.steps()[3].count, c.steps()[2].count);
  EXPECT_LT(c.steps()[2].count, c.steps()[1].count);
  EXPECT_GT(c.feasibleCount(), 0u);
  int listed = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const SpecScene g = specScene(s, c, cfg, seed);
    const scenario::Scenario& sc = g.sc;
    EXPECT_TRUE(g.fails.empty()) << seed << ": " << g.fails.front();
    const scenario::ScenarioEntity* lead = nullptr;
    for (const auto& se : sc.sim.entities) {
      if (!lead && se.role == "target") lead = &se;
    }
    ASSERT_TRUE(lead);
    for (const auto& r : sc.mission.relations) {
      if (r.target_id == lead->entity.id && r.eventually && r.related_class == "garage" &&
          r.op == scenario::RelationOp::kRightOf) {
        ++listed;
        EXPECT_GT(r.time, 0.0);
      }
    }
    // Negative controls: the lead car frozen at its start (nothing comes to its right later),
    // moved 2 km off (nothing beside it at all), and the eventual relation left out of the
    // mission.
    scenario::SimConfig frozen = sc.sim;
    for (auto& se : frozen.entities) {
      if (se.entity.id != lead->entity.id) continue;
      const scenario::TrajectoryPoint p0 = se.trajectory.front();
      se.trajectory = {p0, p0};
      se.trajectory.back().t = 1.0;
    }
    const auto f1 = checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, frozen, nullptr);
    ASSERT_EQ(f1.size(), 1u) << seed;
    EXPECT_EQ(f1[0], "requirement 'garage EVENTUALLY_RIGHT_OF target' does not hold for target " +
                         lead->entity.id + " (recomputed from the scene)");
    scenario::SimConfig away = sc.sim;
    for (auto& se : away.entities) {
      if (se.entity.id != lead->entity.id) continue;
      for (auto& p : se.trajectory) p.x += 2000.0;
    }
    const auto f2 = checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, away, nullptr);
    ASSERT_EQ(f2.size(), 2u) << seed;
    EXPECT_NE(f2[0].find("requirement 'house LEFT_OF target' does not hold"), std::string::npos);
    scenario::Mission unlisted = sc.mission;
    unlisted.relations.erase(
        std::remove_if(unlisted.relations.begin(), unlisted.relations.end(),
                       [](const scenario::SceneRelation& r) { return r.eventually; }),
        unlisted.relations.end());
    const auto f3 = checkScenarioAgainstSpec(s, shippedWorld(), cfg, unlisted, sc.sim, nullptr);
    ASSERT_EQ(f3.size(), 1u) << seed;
    EXPECT_EQ(f3[0],
              "requirement 'garage EVENTUALLY_RIGHT_OF target' holds but the mission does "
              "not list it");
  }
  EXPECT_EQ(listed, 8);
  // The same spec and seed give the same scenario.
  const ScenarioDraw d = c.draw(3, 3, 1, SamplerKind::kRandom);
  const scenario::Scenario a =
      scenario::generateScenario(shippedWorld(), d.config, s.cls, 3, &d.plan);
  const scenario::Scenario b =
      scenario::generateScenario(shippedWorld(), d.config, s.cls, 3, &d.plan);
  EXPECT_EQ(scenario::missionJson(a.mission), scenario::missionJson(b.mission));
  EXPECT_EQ(scenario::simConfigJson(a.sim), scenario::simConfigJson(b.sim));
}

TEST(SpecMoving, PursuitEventuallyIsMetAfterItDrivesOff) {
  const Spec s = parse(
      "scenario pursuit\ntarget car\nrequire pedestrian EVENTUALLY_NEXT_TO target\n"
      "require house EVENTUALLY_LEFT_OF target\n");
  const scenario::GeneratorConfig cfg = specConfig();
  const CompiledSpec c(s, shippedWorld(), cfg);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const SpecScene g = specScene(s, c, cfg, seed);
    const scenario::Scenario& sc = g.sc;
    EXPECT_TRUE(g.fails.empty()) << seed << ": " << g.fails.front();
    // Negative control: the target never leaves its kerb.
    scenario::SimConfig parked = sc.sim;
    for (auto& se : parked.entities) {
      if (se.role != "target") continue;
      const scenario::TrajectoryPoint p0 = se.trajectory.front();
      se.trajectory = {p0, p0};
      se.trajectory.back().t = 1.0;
    }
    const auto f = checkScenarioAgainstSpec(s, shippedWorld(), cfg, sc.mission, parked, nullptr);
    bool reported = false;
    for (const auto& m : f) {
      reported = reported ||
                 m.find("'house EVENTUALLY_LEFT_OF target' does not hold") != std::string::npos;
    }
    EXPECT_TRUE(reported) << seed;
  }
}

TEST(SpecKoz, TypeCheckerRules) {
  auto first = [](const std::string& e) { return e.substr(0, e.find('\n')); };
  const std::string head = std::string(kHead) + "target car parked\n";
  EXPECT_EQ(first(errorOf(head + "koz restricetd over garage\n")),
            "t.hspec:3:5: error: unknown purpose 'restricetd'; did you mean 'restricted'?; "
            "purposes: vantage_denial, access_denial, restricted");
  EXPECT_EQ(first(errorOf(head + "koz restricted garage\n")),
            "t.hspec:3:16: error: expected 'over' after the purpose, got 'garage'");
  const std::string cover = first(errorOf(head + "koz restricted over garag\n"));
  EXPECT_EQ(cover.rfind("t.hspec:3:21: error: unknown zone cover 'garag'; did you mean 'garage'?; "
                        "a zone covers: target, ",
                        0),
            0u)
      << cover;
  EXPECT_EQ(first(errorOf(head + "koz restricted over target { count: 2 }\n")),
            "t.hspec:3:30: error: unknown setting 'count' of a zone over target; settings: alt, "
            "net, nlt, size");
  EXPECT_EQ(first(errorOf(head + "koz restricted over garage { alt: [range(0, 50), 40] }\n")),
            "t.hspec:3:50: error: alt: expected the top of the band above its bottom, whatever "
            "is drawn (40 vs range(0, 50))");
  EXPECT_EQ(first(errorOf(head + "koz restricted over garage { net: 100, nlt: 60..120 }\n")),
            "t.hspec:3:45: error: nlt: expected NLT after NET, whatever is drawn (60..120 vs "
            "100)");
  EXPECT_EQ(first(errorOf(head + "koz restricted over garage { alt: 0 }\n")),
            "t.hspec:3:35: error: expected '[' to open the altitude band: alt: [bottom, top] (m), "
            "got '0'");
  EXPECT_EQ(first(errorOf(head + "koz restricted over garage { count: 9 }\n")),
            "t.hspec:3:37: error: koz1.count: expected values within [1, 5], got 9");
  EXPECT_EQ(first(errorOf(head + "koz restricted over garage { net: 1, net: 2 }\n")),
            "t.hspec:3:43: error: 'net' given twice in this koz");
}

TEST(SpecKoz, ZonesAreAddedAndChecked) {
  const Spec s = parse(
      "scenario route_search\ntarget car moving\n"
      "koz restricted over garage { count: 2, margin: range(3, 6), alt: [0, range(40, 60)], "
      "net: 30..60, nlt: range(300, 400) }\n"
      "koz vantage_denial over target { size: 50 }\n");
  const scenario::GeneratorConfig cfg = specConfig();
  const CompiledSpec c(s, shippedWorld(), cfg);
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const SpecScene g = specScene(s, c, cfg, seed);
    const scenario::Scenario& sc = g.sc;
    EXPECT_TRUE(g.fails.empty()) << seed << ": " << g.fails.front();
    // Three zones after the class's own: two over garages, one over the target.
    const auto& k = sc.mission.kozs;
    ASSERT_GE(k.size(), 3u);
    EXPECT_EQ(k[k.size() - 3].purpose, "restricted");
    EXPECT_EQ(k[k.size() - 2].purpose, "restricted");
    EXPECT_EQ(k.back().purpose, "vantage_denial");
    ASSERT_TRUE(k[k.size() - 3].alt_max && k[k.size() - 3].window.net);
    EXPECT_GE(*k[k.size() - 3].alt_max, 40.0);
    EXPECT_LE(*k[k.size() - 3].alt_max, 60.0);
    EXPECT_FALSE(k.back().alt_max.has_value());
    // Negative controls: a band raised, a zone moved 3 m, a zone dropped.
    scenario::Mission raised = sc.mission;
    *raised.kozs[k.size() - 3].alt_max += 5.0;
    const auto f1 = checkScenarioAgainstSpec(s, shippedWorld(), cfg, raised, sc.sim, nullptr);
    ASSERT_EQ(f1.size(), 1u) << seed;
    EXPECT_EQ(f1[0].rfind("koz restricted over garage: no such keep-out zone in the mission", 0),
              0u)
        << f1[0];
    scenario::Mission moved = sc.mission;
    std::vector<geometry::Vec2> v = moved.kozs.back().polygon.vertices();
    for (auto& p : v) p.x() += 3.0;
    moved.kozs.back().polygon = geometry::Polygon(v);
    const auto f2 = checkScenarioAgainstSpec(s, shippedWorld(), cfg, moved, sc.sim, nullptr);
    ASSERT_EQ(f2.size(), 1u) << seed;
    EXPECT_EQ(f2[0].rfind("koz vantage_denial over target: no such keep-out zone", 0), 0u) << f2[0];
    scenario::Mission dropped = sc.mission;
    dropped.kozs.erase(dropped.kozs.end() - 2);
    EXPECT_EQ(checkScenarioAgainstSpec(s, shippedWorld(), cfg, dropped, sc.sim, nullptr).size(),
              1u);
  }
}

TEST(SpecWithin, TheTargetParksNearALandmarkAndIsChecked) {
  const Spec s = parse(std::string(kHead) + "target car parked within 25 of intersection\n");
  int far = 0;
  for (const auto& sc : generateChecked(s, 12)) {
    const scenario::ScenarioEntity* target = nullptr;
    for (const auto& se : sc.sim.entities) {
      if (se.role == "target") target = &se;
    }
    ASSERT_TRUE(target);
    double nearest = 1e18;
    for (const auto& n : shippedWorld().nodes())
      nearest = std::min(nearest, (n.position - target->entity.box.center2()).norm());
    EXPECT_LE(nearest, 25.0);
    // Negative control: the same scene with the target moved to a place far from every
    // intersection.
    scenario::SimConfig moved = sc.sim;
    for (const auto& sl : shippedWorld().slots()) {
      double d = 1e18;
      for (const auto& n : shippedWorld().nodes())
        d = std::min(d, (n.position - sl.position).norm());
      if (d < 40.0) continue;
      for (auto& se : moved.entities) {
        if (se.role == "target") se.entity.box.center.head<2>() = sl.position;
      }
      break;
    }
    const auto f = checkOf(s, sc, moved);
    ASSERT_FALSE(f.empty());
    EXPECT_NE(f[0].find("is not within 25 of intersection"), std::string::npos) << f[0];
    ++far;
  }
  EXPECT_EQ(far, 12);
  // A landmark the world lacks is a name error; a distance no place meets is unsatisfiable.
  const std::string bus = errorOf(std::string(kHead) + "target car parked within 80 of bus_stp\n");
  EXPECT_EQ(bus.substr(0, bus.find(';')), "t.hspec:2:32: error: unknown landmark 'bus_stp'");
  const Spec tight = parse(std::string(kHead) + "target car parked within 0.5 of intersection\n");
  const std::string m = messageOf([&] { CompiledSpec(tight, shippedWorld(), shippedConfig()); });
  EXPECT_EQ(m.find("t.hspec:2:19: error: unsatisfiable in this world: target within 0.5 of "
                   "intersection: 0 of "),
            0u)
      << m;
}

TEST(SpecConfusers, ShareDistanceAndToldApartAreMetAndChecked) {
  const Spec s = parse(std::string(kHead) +
                       "target car {make: Chevrolet, model: Impala, color: blue} parked\n"
                       "require garage LEFT_OF target {color: white}\n"
                       "confusers { count: 4, share: [vehicle_class, color], within: 250,\n"
                       "  told_apart_by: \"garage LEFT_OF target {color: white}\" }\n");
  int confusers = 0;
  for (const auto& sc : generateChecked(s, 10)) {
    const scenario::ScenarioEntity* target = nullptr;
    for (const auto& se : sc.sim.entities) {
      if (se.role == "target") target = &se;
    }
    ASSERT_TRUE(target);
    for (std::size_t i = 0; i < sc.sim.entities.size(); ++i) {
      const auto& c = sc.sim.entities[i];
      if (c.role != "confuser") continue;
      ++confusers;
      EXPECT_EQ(c.entity.attributes.str("vehicle_class"), "sedan");
      EXPECT_EQ(c.entity.attributes.str("color"), "blue");
      EXPECT_NE(c.entity.attributes.str("model"), "Impala");
      EXPECT_LE((c.entity.box.center2() - target->entity.box.center2()).norm(), 250.0 + 1e-3);
      // Negative controls: another colour; parked 1 km away; parked where the target is (its
      // garage on the left tells nothing apart there).
      scenario::SimConfig color = sc.sim;
      color.entities[i].entity.attributes.set("color", std::string("red"));
      auto f = checkOf(s, sc, color);
      ASSERT_EQ(f.size(), 1u);
      EXPECT_EQ(f[0], "confuser " + c.entity.id + ": color 'red' differs from the target's");
      scenario::SimConfig far = sc.sim;
      far.entities[i].entity.box.center.x() += 1000.0;
      f = checkOf(s, sc, far);
      ASSERT_FALSE(f.empty());
      EXPECT_EQ(f[0].find("confusers.within: confuser " + c.entity.id + " parks"), 0u) << f[0];
      scenario::SimConfig same = sc.sim;
      same.entities[i].entity.box = target->entity.box;
      f = checkOf(s, sc, same);
      ASSERT_FALSE(f.empty());
      EXPECT_NE(std::find(f.begin(), f.end(),
                          "confuser " + c.entity.id +
                              " meets 'garage LEFT_OF target {color: white}', which should tell "
                              "it apart"),
                f.end());
    }
  }
  EXPECT_GE(confusers, 20);  // of at most 40
  const std::string share =
      errorOf(std::string(kHead) + "target car parked\nconfusers { share: [colour] }\n");
  EXPECT_EQ(share.substr(0, share.find('?') + 1),
            "t.hspec:3:21: error: unknown attribute 'colour' to share; did you mean 'color'?");
  const std::string told = errorOf(std::string(kHead) +
                                   "target car parked\nrequire garage LEFT_OF target\n"
                                   "confusers { told_apart_by: \"tree NEXT_TO target\" }\n");
  EXPECT_EQ(told.substr(0, told.find('\n')),
            "t.hspec:4:28: error: told_apart_by: 'tree NEXT_TO target' is not a hard requirement "
            "on the neighborhood of this spec; its requirements: garage LEFT_OF target");
}

TEST(SpecWorld, TheSpecNamesItsWorldAndOtherWorldsRefuseIt) {
  const std::string city = errorOf("world city\n" + std::string(kHead) + "target car parked\n");
  EXPECT_EQ(city.substr(0, city.find('\n')),
            "t.hspec:1:7: error: this spec is written for the city world; the world here is "
            "suburb (hameritt_generate builds the spec's world; --world must agree)");
  EXPECT_NO_THROW(parse("world suburb\n" + std::string(kHead) + "target car parked\n"));
  const std::string typo = errorOf("world citty\n" + std::string(kHead));
  EXPECT_EQ(typo.substr(0, typo.find('?') + 1),
            "t.hspec:1:7: error: unknown world type 'citty'; did you mean 'city'?");
  // specWorld() reads it before the world is built, through imports; the last one wins.
  const auto dir = std::filesystem::temp_directory_path() / "hameritt_spec_world_test";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "base.hspec") << "world city\nenvironment { fog: 0.1 }\n";
  std::ofstream(dir / "a.hspec") << "import \"base.hspec\"\nscenario area_search\n";
  std::ofstream(dir / "b.hspec") << "import \"base.hspec\"\nworld suburb\n";
  std::ofstream(dir / "c.hspec") << "scenario area_search\nconfusers { count: 2 }\n";
  EXPECT_EQ(specWorld((dir / "a.hspec").string()), "city");
  EXPECT_EQ(specWorld((dir / "b.hspec").string()), "suburb");
  EXPECT_EQ(specWorld((dir / "c.hspec").string()), "");
  EXPECT_EQ(specWorld((dir / "missing.hspec").string()), "");
  std::filesystem::remove_all(dir);
}

TEST(SpecNames, EditDistance) {
  EXPECT_EQ(editDistance("kitten", "sitting"), 3);
  EXPECT_EQ(editDistance("", "abc"), 3);
  EXPECT_EQ(editDistance("snwo", "snow"), 1);  // a swap of two neighbours
  EXPECT_EQ(nearestNames("gren", {"green", "grey", "red", "blue"}),
            (std::vector<std::string>{"green", "grey"}));
}

}  // namespace
}  // namespace hameritt::generation
