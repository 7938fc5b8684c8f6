// hameritt_world: writes the neighborhood (street graph, blocks, parking slots, every entity)
// as JSON, for inspection and for outside tools, and measures its density and occlusion.
//   hameritt_world [--world-config FILE] [--world suburb|city] [--seed S] [--out FILE]
//                  [--metrics FILE|-]
// Exit codes: 0 success, 2 bad input or unwritable output.

#include <cstdio>
#include <string>

#include "hameritt/scenario/error.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/world_metrics.h"

using namespace hameritt::scenario;

int main(int argc, char** argv) {
  std::string cfg = defaultConfigDir() + "/world.json", out;
  std::string seed, type, metrics;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw ConfigError(a + ": missing value");
        return argv[++i];
      };
      if (a == "-h" || a == "--help") {
        std::fputs(
            "usage: hameritt_world [--world-config FILE] [--world suburb|city] [--seed S]\n"
            "                      [--out FILE] [--metrics FILE|-]\n"
            "  --metrics: density and occlusion figures as JSON (- for stdout)\n",
            stdout);
        return 0;
      }
      if (a == "--world-config") cfg = next();
      else if (a == "--seed") seed = next();
      else if (a == "--out") out = next();
      else if (a == "--world")
        type = next();
      else if (a == "--metrics")
        metrics = next();
      else throw ConfigError("unknown argument '" + a + "'");
    }
    if (out.empty() && metrics.empty()) throw ConfigError("--out or --metrics is required");
    WorldParams p = loadWorldParams(cfg);
    if (!type.empty() && !parseWorldType(type, &p.type)) {
      throw ConfigError("--world: expected suburb or city, got '" + type + "'");
    }
    if (!seed.empty()) {
      if (seed.find_first_not_of("0123456789") != std::string::npos) {
        throw ConfigError("--seed: expected a non-negative integer, got '" + seed + "'");
      }
      p.seed = std::stoull(seed);
    }
    const World w = generateWorld(p);
    if (!out.empty()) {
      writeFileAtomic(out, worldJson(w));
      std::fprintf(stderr, "hameritt_world: %zu entities, fingerprint %s -> %s\n",
                   w.entities().size(), hex64(w.fingerprint()).c_str(), out.c_str());
    }
    if (!metrics.empty()) {
      const std::string text = metricsJson(measureWorld(w));
      if (metrics == "-")
        std::fputs(text.c_str(), stdout);
      else
        writeFileAtomic(metrics, text);
    }
    return 0;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "hameritt_world: error: %s\n", e.what());
    return 2;
  } catch (const OutputError& e) {
    std::fprintf(stderr, "hameritt_world: error: %s\n", e.what());
    return 2;
  }
}
