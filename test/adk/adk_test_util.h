#pragma once
// Shared fixtures of the ADK tests: small hand-made missions and the shipped scenario.

#include "hameritt/build_paths.h"
#include <cstdint>
#include <string>

#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/sim_config_io.h"

namespace hameritt::adk::testing {

using geometry::Polygon;
using geometry::Vec2;
using geometry::Vec3;

inline Polygon square(double x0, double y0, double x1, double y1) {
  return Polygon({Vec2(x0, y0), Vec2(x1, y0), Vec2(x1, y1), Vec2(x0, y1)});
}

inline scenario::KeepOutZone koz(const std::string& id, Polygon p, std::optional<double> zmin,
                                 std::optional<double> zmax,
                                 geometry::TimeWindow w = geometry::TimeWindow{}) {
  scenario::KeepOutZone k;
  k.id = id;
  k.purpose = "restricted";
  k.polygon = std::move(p);
  k.alt_min = zmin;
  k.alt_max = zmax;
  k.window = w;
  return k;
}

inline geometry::TimeWindow window(std::optional<double> net, std::optional<double> nlt) {
  geometry::TimeWindow w;
  w.net = net;
  w.nlt = nlt;
  return w;
}

// One keep-out zone: the square [0, 10]^2 between 5 m and 20 m, always active.
inline scenario::Mission squareMission(geometry::TimeWindow w = {}) {
  scenario::Mission m;
  m.scenario_id = "test";
  m.time_limit = 100;
  m.objective.type = "find";
  m.kozs.push_back(koz("koz_a", square(0, 0, 10, 10), 5.0, 20.0, w));
  return m;
}

inline const scenario::Mission& shippedMission() {
  static const scenario::Mission m =
      scenario::loadMission(std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/mission.json");
  return m;
}

inline const scenario::SimConfig& shippedSimConfig() {
  static const scenario::SimConfig s = scenario::loadSimConfig(
      std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/sim_config.json");
  return s;
}

// The shipped mission with time windows on its keep-out zones (test/data).
inline const scenario::Mission& windowsMission() {
  static const scenario::Mission m =
      scenario::loadMission(std::string(HAMERITT_TEST_DATA_DIR) + "/adk_windows_mission.json");
  return m;
}

// A small seeded generator (splitmix64) with our own uniform doubles, so that test inputs are
// the same on every standard library.
class TestRng {
 public:
  explicit TestRng(std::uint64_t seed) : s_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(next() >> 11) * 0x1.0p-53);
  }

 private:
  std::uint64_t s_;
};

}  // namespace hameritt::adk::testing
