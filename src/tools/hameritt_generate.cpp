// hameritt_generate: random scenarios as mission.json + sim_config.json, with a manifest.
//   hameritt_generate --class area_search|route_search|pursuit|avoid|follow|track|all
//                     --count N --seed S
//                     --out DIR
//                     [--first K] [--jobs J] [--world-config FILE] [--world suburb|city]
//                     [--generator-config FILE]
//   hameritt_generate --class CLASS --scenario-seed S --out DIR   (regenerates one scenario)
//   hameritt_generate --spec FILE [--param NAME=VALUE ...] [--sampler random|halton] --count N
//                     --seed S --out DIR [--jobs J]       (scenarios from a scenario-language spec)
//   hameritt_generate --spec FILE ... --verify   (each scenario also re-checked against the
//                     spec before it is written, as hameritt_validate --spec checks files)
//   hameritt_generate ... --seed S --into DIR   (one scenario: DIR/mission.json,
//   DIR/sim_config.json)
// Exit codes: 0 success, 2 bad input (a malformed or unsatisfiable spec, an unknown or repeated
// --param) or unwritable output, 1 generation failure. On exit 2 nothing is written.

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "hameritt/generation/batch.h"
#include "hameritt/generation/generator.h"
#include "hameritt/generation/spec_sampler.h"
#include "hameritt/scenario/error.h"

using namespace hameritt::scenario;

namespace {

// A command-line mistake: reported with the usage. A bad configuration file is a ConfigError
// naming the file and field, reported without it.
struct UsageError : ConfigError {
  using ConfigError::ConfigError;
};

const char* kUsage =
    "usage: hameritt_generate --class CLASS --count N --seed S --out DIR [--first K] [--jobs J]\n"
    "                         [--world-config FILE] [--world suburb|city]\n"
    "                         [--generator-config FILE] [--quiet]\n"
    "       hameritt_generate --class CLASS --scenario-seed S --out DIR   (one scenario, seed S)\n"
    "       hameritt_generate --spec FILE [--param NAME=VALUE ...] [--sampler random|halton]\n"
    "                         --count N --seed S --out DIR [--jobs J] [--verify]\n"
    "       hameritt_generate (--class CLASS | --spec FILE ...) --seed S --into DIR\n"
    "  --into DIR: scenario 0 of the batch, its mission.json and sim_config.json written into\n"
    "  DIR itself (replacing those files; no manifest), e.g. for mission.launch spec:=FILE.\n"
    "  CLASS: area_search, route_search, pursuit, avoid, follow, track, all (the three\n"
    "  search classes), or a comma-separated list\n"
    "  Scenario i of a batch has class CLASS[i mod k] and a seed derived from S and i.\n"
    "  --first K: write only indices K..K+N-1 of the batch (a shard), byte-identical to them.\n"
    "  --world: the world type, overriding the world config's \"type\" (default suburb).\n"
    "  --verify: re-check each scenario against the spec before it is written (the check of\n"
    "  hameritt_validate --spec, on the scene in memory); one that fails fails the batch\n"
    "  (exit 1). Prints the soft requirements' counts and \"N scenarios verified against the\n"
    "  spec\".\n";

std::uint64_t parseUnsigned(const std::string& flag, const std::string& v) {
  if (v.empty() || v[0] == '-' || v.find_first_not_of("0123456789") != std::string::npos) {
    throw UsageError(flag + ": expected a non-negative integer, got '" + v + "'");
  }
  try {
    return std::stoull(v);
  } catch (...) {
    throw UsageError(flag + ": number out of range: '" + v + "'");
  }
}

long parseCount(const std::string& flag, const std::string& v) {
  if (!v.empty() && v[0] == '-') {
    throw UsageError(flag + ": expected a positive integer, got '" + v + "'");
  }
  const std::uint64_t n = parseUnsigned(flag, v);
  if (n == 0 || n > 10000000) throw UsageError(flag + ": expected 1 to 10000000, got " + v);
  return static_cast<long>(n);
}

}  // namespace

int main(int argc, char** argv) {
  std::string cls, out, into, world_type, world_cfg = defaultConfigDir() + "/world.json";
  std::string gen_cfg = defaultConfigDir() + "/generator.json";
  long count = -1, first = 0;
  std::uint64_t seed = 0;
  bool have_seed = false, quiet = false, exact = false, verify = false;
  std::string spec_file, sampler_name = "random";
  std::vector<std::string> params;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  hameritt::scenario::keepFreedMemoryForBatches();
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw UsageError(a + ": missing value");
        return argv[++i];
      };
      if (a == "--class")
        cls = next();
      else if (a == "--count")
        count = parseCount(a, next());
      else if (a == "--seed")
        seed = parseUnsigned(a, next()), have_seed = true;
      else if (a == "--scenario-seed")
        seed = parseUnsigned(a, next()), have_seed = exact = true;
      else if (a == "--first") {
        const std::uint64_t k = parseUnsigned(a, next());
        if (k > 10000000) {
          throw UsageError("--first: expected 0 to 10000000, got " + std::to_string(k));
        }
        first = static_cast<long>(k);
      } else if (a == "--out")
        out = next();
      else if (a == "--into")
        into = next();
      else if (a == "--jobs")
        jobs = static_cast<int>(parseCount(a, next()));
      else if (a == "--world-config")
        world_cfg = next();
      else if (a == "--world")
        world_type = next();
      else if (a == "--generator-config")
        gen_cfg = next();
      else if (a == "--quiet")
        quiet = true;
      else if (a == "--verify")
        verify = true;
      else if (a == "--spec")
        spec_file = next();
      else if (a == "--param")
        params.push_back(next());
      else if (a == "--sampler")
        sampler_name = next();
      else if (a == "-h" || a == "--help") {
        std::fputs(kUsage, stdout);
        return 0;
      } else {
        throw UsageError("unknown argument '" + a + "'");
      }
    }
    if (cls.empty() && spec_file.empty()) throw UsageError("--class is required (or --spec FILE)");
    if (!cls.empty() && !spec_file.empty()) {
      throw UsageError("--class: a spec names its class; give --class or --spec, not both");
    }
    if (spec_file.empty() && !params.empty()) throw UsageError("--param: needs --spec");
    if (spec_file.empty() && verify) throw UsageError("--verify: needs --spec");
    hameritt::generation::SamplerKind sampler;
    if (!hameritt::generation::parseSampler(sampler_name, &sampler)) {
      throw UsageError("--sampler: expected random or halton, got '" + sampler_name + "'");
    }
    if (!into.empty()) {
      if (!out.empty()) throw UsageError("--into: give --out or --into, not both");
      if (count > 1) throw UsageError("--into: writes one scenario; --count must be 1");
      if (first != 0) throw UsageError("--into: cannot be combined with --first");
      count = 1;
      // Generated beside DIR, then moved into it file by file (each rename atomic): a failed
      // run leaves DIR as it was.
      std::filesystem::path dir(into);
      out = (dir.has_filename() ? dir : dir.parent_path()).string() + ".tmp." +
            std::to_string(::getpid());
    }
    if (count < 0 && exact) count = 1;
    if (count < 0) throw UsageError("--count is required");
    if (!have_seed) throw UsageError("--seed (or --scenario-seed) is required");
    if (out.empty()) throw UsageError("--out is required");

    BatchRequest req;
    if (!cls.empty()) req.classes = parseClassList(cls);
    req.count = static_cast<int>(count);
    req.first = static_cast<int>(first);
    req.seed = seed;
    req.out_dir = out;
    req.jobs = jobs;
    req.exact_seed = exact;
    WorldParams wp = loadWorldParams(world_cfg);
    // A spec's `world suburb|city` picks the world unless --world does (an unknown name is
    // reported by the parse, with its place).
    if (world_type.empty() && !spec_file.empty()) {
      const std::string w = hameritt::generation::specWorld(spec_file);
      hameritt::scenario::WorldType t;
      if (parseWorldType(w, &t)) world_type = w;
    }
    if (!world_type.empty()) {
      if (!parseWorldType(world_type, &wp.type)) {
        throw UsageError("--world: expected suburb or city, got '" + world_type + "'");
      }
      wp.validate();
    }
    const GeneratorConfig gc = loadGeneratorConfig(gen_cfg);
    const auto t0 = std::chrono::steady_clock::now();
    const World world = generateWorld(wp);
    std::unique_ptr<hameritt::generation::CompiledSpec> compiled;
    if (!spec_file.empty()) {
      // Parsed, type-checked and compiled before anything is written.
      compiled = std::make_unique<hameritt::generation::CompiledSpec>(
          hameritt::generation::parseSpec(spec_file, params, world), world, gc);
      req.spec = compiled.get();
      req.sampler = sampler;
    }
    // --verify: the independent checker on every scenario, the soft requirements counted in
    // the order of the spec (the same counts whatever the thread count).
    std::mutex verify_mu;
    std::vector<std::string> soft_names;
    std::vector<long> soft_held;
    if (verify) {
      req.check = [&](const Scenario& s) {
        std::vector<hameritt::generation::RequirementCheck> soft;
        const auto fails = hameritt::generation::checkScenarioAgainstSpec(
            compiled->spec(), world, gc, s.mission, s.sim, &soft);
        if (!fails.empty()) {
          throw GenerationError(s.mission.scenario_id +
                                " does not meet the spec: " + fails.front());
        }
        std::lock_guard<std::mutex> lock(verify_mu);
        for (std::size_t i = 0; i < soft.size(); ++i) {
          if (soft_names.size() <= i) {
            soft_names.push_back(soft[i].requirement);
            soft_held.push_back(0);
          }
          soft_held[i] += soft[i].holds ? 1 : 0;
        }
      };
    }
    if (!into.empty()) req.write_world = false;
    // A city scenario's traffic is a reference to an episode file; a single scenario's file lies
    // in its own directory, so that the directory stands alone.
    req.share_traffic = true;
    req.traffic_inside = !into.empty();
    std::vector<hameritt::scenario::ManifestEntry> entries;
    try {
      entries = generateBatch(world, gc, req);
    } catch (...) {
      std::error_code ec;
      if (!into.empty()) std::filesystem::remove_all(out, ec);
      throw;
    }
    if (!into.empty()) {
      namespace fs = std::filesystem;
      std::error_code ec;
      const std::string from = out + "/" + entries.at(0).id;
      fs::create_directories(into, ec);
      if (ec || !fs::is_directory(into)) {
        fs::remove_all(out, ec);
        throw OutputError(into + ": cannot create directory");
      }
      // The episode file first: sim_config.json never names a file that is not there.
      std::vector<std::string> files;
      for (const auto& entry : fs::directory_iterator(from, ec)) {
        const std::string name = entry.path().filename().string();
        if (name.rfind("traffic_episode_", 0) == 0) files.push_back(name);
      }
      files.push_back("sim_config.json");
      files.push_back("mission.json");
      for (const std::string& f : files) {
        fs::rename(from + "/" + f, into + "/" + f, ec);
        if (ec) {
          const std::string why = ec.message();
          fs::remove_all(out, ec);
          throw OutputError(into + "/" + f + ": cannot write: " + why);
        }
      }
      fs::remove_all(out, ec);
      out = into;
    }
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (verify) {
      for (std::size_t i = 0; i < soft_names.size(); ++i) {
        std::printf("soft '%s': held in %ld of %zu scenarios\n", soft_names[i].c_str(),
                    soft_held[i], entries.size());
      }
      std::printf("%zu scenarios verified against the spec\n", entries.size());
    }
    if (!quiet) {
      for (const auto& e : entries) std::printf("%s\n", e.id.c_str());
      std::fprintf(stderr, "hameritt_generate: %zu scenarios in %s (%.3f s, %d jobs)\n",
                   entries.size(), out.c_str(), secs, jobs);
    }
    return 0;
  } catch (const hameritt::generation::SpecError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const UsageError& e) {
    std::fprintf(stderr, "hameritt_generate: error: %s\n%s", e.what(), kUsage);
    return 2;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "hameritt_generate: error: %s\n", e.what());
    return 2;
  } catch (const OutputError& e) {
    std::fprintf(stderr, "hameritt_generate: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hameritt_generate: generation failed: %s\n", e.what());
    return 1;
  }
}
