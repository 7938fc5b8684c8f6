// hameritt_validate: checks scenario documents against config/schema/ and the semantic rules.
//   hameritt_validate [--schema-dir DIR] FILE...
//   hameritt_validate --spec FILE [--param NAME=VALUE ...] DIR...
// Prints "FILE: ok" on stdout for each valid file and one "FILE: PATH: RULE: MESSAGE" line on
// stderr per issue. With --spec, each DIR is a scenario directory or a batch directory (every
// subdirectory holding a sim_config.json): the spec's hard requirements are re-checked from
// the scene (relations recomputed), "DIR: ok" or "DIR: MESSAGE" lines per scenario, then one
// "soft 'REQUIREMENT': held in K of N scenarios" line per soft requirement and a total.
// An avoid scenario's sim_config.json with a mission.json beside it is also checked against its
// regenerated world (start and goal clear, the goal reachable, the stated shortest path, the
// aircraft continuous and clear of obstacles): rule "avoid_scenario".
// Exit codes: 0 all files valid, 2 any issue or bad usage.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "hameritt/generation/avoid.h"
#include "hameritt/generation/generator.h"
#include "hameritt/generation/spec_sampler.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/validation.h"

using namespace hameritt::scenario;

namespace {

const char* kUsage =
    "usage: hameritt_validate [--schema-dir DIR] FILE...\n"
    "  Validates mission.json, sim_config.json, world.json and manifest.json files (the kind\n"
    "  comes from each file's \"schema\" field). DIR defaults to the package's config/schema.\n"
    "       hameritt_validate --spec FILE [--param NAME=VALUE ...] [--generator-config FILE] "
    "DIR...\n"
    "  Re-checks every hard requirement of the spec on the scenarios in each DIR, from the "
    "scene.\n";

int usageError(const std::string& message) {
  std::fprintf(stderr, "hameritt_validate: error: %s\n%s", message.c_str(), kUsage);
  return 2;
}

namespace fs = std::filesystem;

// Scenario directories under each argument: the directory itself when it holds a
// sim_config.json, else its subdirectories that do, sorted.
std::vector<std::string> scenarioDirs(const std::vector<std::string>& args) {
  std::vector<std::string> out;
  for (const auto& a : args) {
    std::error_code ec;
    if (fs::exists(fs::path(a) / "sim_config.json", ec)) {
      out.push_back(a);
      continue;
    }
    std::vector<std::string> sub;
    for (const auto& e : fs::directory_iterator(a, ec)) {
      if (fs::exists(e.path() / "sim_config.json", ec)) sub.push_back(e.path().string());
    }
    if (sub.empty()) throw ConfigError(a + ": no sim_config.json in it or in its subdirectories");
    std::sort(sub.begin(), sub.end());
    out.insert(out.end(), sub.begin(), sub.end());
  }
  return out;
}

// The avoid_scenario issues of a valid sim_config.json (none for other classes, or without a
// mission.json beside it).
std::vector<ValidationIssue> avoidIssues(const std::string& sim_file) {
  const fs::path mission_file = fs::path(sim_file).parent_path() / "mission.json";
  std::error_code ec;
  if (fs::path(sim_file).filename() != "sim_config.json" || !fs::exists(mission_file, ec)) {
    return {};
  }
  std::vector<ValidationIssue> out;
  try {
    const SimConfig sim = loadSimConfig(sim_file);
    if (sim.cls != ScenarioClass::kAvoid) return {};
    const Mission mission = loadMission(mission_file.string());
    const World world = generateCheckedWorld(sim, sim_file);
    for (const auto& m : checkAvoidScenario(world, mission, sim)) {
      out.push_back({sim_file, "", "avoid_scenario", m});
    }
  } catch (const std::exception& e) {
    out.push_back({sim_file, "", "avoid_scenario", e.what()});
  }
  return out;
}

int validateSpec(const std::string& spec_file, const std::vector<std::string>& params,
                 const std::string& gen_cfg, const std::vector<std::string>& args) {
  namespace gen = hameritt::generation;
  try {
    const GeneratorConfig base = loadGeneratorConfig(gen_cfg);
    const std::vector<std::string> dirs = scenarioDirs(args);
    std::map<std::uint64_t, std::unique_ptr<World>> worlds;
    std::unique_ptr<gen::Spec> spec;
    std::vector<std::string> soft_names;
    std::vector<long> soft_held;
    long failed = 0;
    for (const auto& d : dirs) {
      const std::string sim_file = d + "/sim_config.json";
      SimConfig sim;
      Mission mission;
      try {
        sim = loadSimConfig(sim_file);
        mission = loadMission(d + "/mission.json");
      } catch (const ConfigError& e) {
        // An unreadable scenario fails the spec; the others are still checked.
        ++failed;
        std::fprintf(stderr, "%s: %s\n", d.c_str(), e.what());
        continue;
      }
      auto& w = worlds[sim.world_fingerprint];
      if (!w) w = std::make_unique<World>(generateCheckedWorld(sim, sim_file));
      if (!spec) spec = std::make_unique<gen::Spec>(gen::parseSpec(spec_file, params, *w));
      std::vector<gen::RequirementCheck> soft;
      const auto fails = gen::checkScenarioAgainstSpec(*spec, *w, base, mission, sim, &soft);
      for (std::size_t i = 0; i < soft.size(); ++i) {
        if (soft_names.size() <= i) {
          soft_names.push_back(soft[i].requirement);
          soft_held.push_back(0);
        }
        soft_held[i] += soft[i].holds ? 1 : 0;
      }
      if (fails.empty()) {
        std::printf("%s: ok\n", d.c_str());
      } else {
        ++failed;
        for (const auto& f : fails) std::fprintf(stderr, "%s: %s\n", d.c_str(), f.c_str());
      }
    }
    for (std::size_t i = 0; i < soft_names.size(); ++i) {
      std::printf("soft '%s': held in %ld of %zu scenarios\n", soft_names[i].c_str(), soft_held[i],
                  dirs.size());
    }
    std::printf("%zu scenarios, %zu meet the spec, %ld fail\n", dirs.size(),
                dirs.size() - static_cast<std::size_t>(failed), failed);
    std::fflush(stdout);
    return failed == 0 ? 0 : 2;
  } catch (const gen::SpecError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hameritt_validate: error: %s\n", e.what());
    return 2;
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string schema_dir = defaultConfigDir() + "/schema";
  std::vector<std::string> files;
  std::string spec_file, gen_cfg = defaultConfigDir() + "/generator.json";
  std::vector<std::string> params;
  bool options_done = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (options_done || a.empty() || a[0] != '-' || a == "-") {
      files.push_back(a);
    } else if (a == "--") {
      options_done = true;
    } else if (a == "--schema-dir") {
      if (i + 1 >= argc) return usageError("--schema-dir: missing value");
      schema_dir = argv[++i];
    } else if (a == "--spec" || a == "--param" || a == "--generator-config") {
      if (i + 1 >= argc) return usageError(a + ": missing value");
      const std::string v = argv[++i];
      if (a == "--spec") {
        spec_file = v;
      } else if (a == "--param") {
        params.push_back(v);
      } else {
        gen_cfg = v;
      }
    } else if (a == "-h" || a == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    } else {
      return usageError("unknown argument '" + a + "'");
    }
  }
  if (files.empty()) return usageError(spec_file.empty() ? "no FILE given" : "no DIR given");
  if (!spec_file.empty()) return validateSpec(spec_file, params, gen_cfg, files);
  if (!params.empty()) return usageError("--param: needs --spec");
  std::error_code ec;
  if (!std::filesystem::is_directory(schema_dir, ec)) {
    return usageError("--schema-dir: '" + schema_dir + "' is not a directory");
  }

  bool all_ok = true;
  for (const auto& f : files) {
    std::vector<ValidationIssue> issues = validateFile(f, schema_dir);
    if (issues.empty()) issues = avoidIssues(f);
    if (issues.empty()) {
      std::printf("%s: ok\n", f.c_str());
      continue;
    }
    all_ok = false;
    for (const auto& issue : issues) std::fprintf(stderr, "%s\n", formatIssue(issue).c_str());
  }
  std::fflush(stdout);
  return all_ok ? 0 : 2;
}
