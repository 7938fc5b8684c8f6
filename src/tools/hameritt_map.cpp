// hameritt_map: draws a top-down map of one scenario (world, AOIs with priors, keep-out zones,
// routes, movers and their trajectories, UAV start) as a PNG.
//   hameritt_map SCENARIO_DIR --out FILE.png [--px-per-m X] [--full]
// Exit codes: 0 success, 2 bad input or unwritable output, 1 unexpected failure.

#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include "hameritt/map/scenario_map.h"
#include "hameritt/scenario/error.h"

using hameritt::scenario::ConfigError;
using hameritt::scenario::OutputError;

namespace {

const char* kUsage =
    "usage: hameritt_map SCENARIO_DIR --out FILE.png [--px-per-m X] [--full]\n"
    "  SCENARIO_DIR  directory with mission.json and sim_config.json\n"
    "  --px-per-m X  map scale in pixels per metre (default 1.2)\n"
    "  --full        draw the whole neighborhood instead of cropping to the mission area\n";

double parsePositive(const std::string& flag, const std::string& v) {
  double x = 0.0;
  if (!hameritt::scenario::parseNumber(v, &x) || x <= 0.0) {
    throw ConfigError(flag + ": expected a positive number, got '" + v + "'");
  }
  return x;
}

}  // namespace

int main(int argc, char** argv) {
  std::string dir, out;
  hameritt::map::MapStyle style;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw ConfigError(a + ": missing value");
        return argv[++i];
      };
      if (a == "--out") {
        out = next();
      } else if (a == "--px-per-m") {
        style.px_per_m = parsePositive(a, next());
      } else if (a == "--full") {
        style.crop_to_interest = false;
      } else if (a == "-h" || a == "--help") {
        std::fputs(kUsage, stdout);
        return 0;
      } else if (!a.empty() && a[0] == '-') {
        throw ConfigError("unknown option '" + a + "'");
      } else if (dir.empty()) {
        dir = a;
      } else {
        throw ConfigError("unexpected argument '" + a + "' (one scenario directory expected)");
      }
    }
    if (dir.empty()) throw ConfigError("SCENARIO_DIR is required");
    if (out.empty()) throw ConfigError("--out is required");
    hameritt::map::writeScenarioMap(dir, out, style);
    std::fprintf(stderr, "hameritt_map: %s -> %s\n", dir.c_str(), out.c_str());
    return 0;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "hameritt_map: error: %s\n", e.what());
    return 2;
  } catch (const OutputError& e) {
    std::fprintf(stderr, "hameritt_map: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hameritt_map: failed: %s\n", e.what());
    return 1;
  }
}
