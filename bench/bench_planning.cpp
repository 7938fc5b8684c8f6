// Planning benchmark: RRT-Connect UAV crossings of the default neighborhood with 5 keep-out
// zones, and car routes. Prints median and p95 planning times and the success rate.
// Usage: bench_planning [--count N]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "hameritt/planning/uav_planner.h"
#include "hameritt/planning/vehicle_routes.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/rng.h"

using namespace hameritt;
using geometry::Vec2;
using geometry::Vec3;

namespace {

void report(const char* what, std::vector<double> ms, int ok, int total) {
  std::sort(ms.begin(), ms.end());
  const double med = ms.empty() ? 0 : ms[ms.size() / 2];
  const double p95 = ms.empty() ? 0 : ms[std::min(ms.size() - 1, ms.size() * 95 / 100)];
  std::printf("%-34s n=%4d  median %7.2f ms  p95 %7.2f ms  success %5.1f%%\n", what, total, med,
              p95, 100.0 * ok / total);
}

}  // namespace

int main(int argc, char** argv) {
  int count = 200;
  for (int i = 1; i + 1 < argc; ++i) {
    if (!std::strcmp(argv[i], "--count")) count = std::atoi(argv[i + 1]);
  }
  const scenario::World world =
      scenario::generateWorld(scenario::loadWorldParams(scenario::defaultConfigDir() + "/world.json"));
  const auto b = world.bounds();
  scenario::Rng rng(1);
  // Five keep-out zones, two with time windows, all altitudes.
  std::vector<scenario::KeepOutZone> kozs;
  for (int k = 0; k < 5; ++k) {
    const Vec2 c(rng.uniform(-300, 300), rng.uniform(-300, 300));
    const Vec2 h(rng.uniform(30, 70), rng.uniform(30, 70));
    scenario::KeepOutZone z;
    z.id = "koz_" + std::to_string(k);
    z.purpose = "restricted";
    z.polygon = geometry::rectangle(c - h, c + h);
    if (k >= 3) {
      z.window.net = rng.uniform(0, 60);
      z.window.nlt = *z.window.net + 60;
    }
    kozs.push_back(z);
  }
  for (const auto& [label, zmin, zmax] :
       {std::tuple<const char*, double, double>{"UAV RRT-Connect crossing, band 21-76", 21, 76},
        std::tuple<const char*, double, double>{"UAV RRT-Connect crossing, band 3-30", 3, 30}}) {
    planning::ValiditySettings vs;
    vs.altitude_min = zmin;
    vs.altitude_max = zmax;
    const planning::WorldValidity v(world, kozs, vs);
    std::vector<double> ms;
    int ok = 0, total = 0;
    for (int i = 0; i < count; ++i) {
      // West edge to east edge, at random altitudes; endpoints that are invalid are redrawn.
      Vec3 s, g;
      do {
        s = Vec3(b.min.x() + 5, rng.uniform(b.min.y() + 5, b.max.y() - 5), rng.uniform(zmin, zmax));
      } while (!v.valid(s, 0.0));
      do {
        g = Vec3(b.max.x() - 5, rng.uniform(b.min.y() + 5, b.max.y() - 5), rng.uniform(zmin, zmax));
      } while (!v.staticValid(g) || !v.kozClear(g, 0, 1e9));
      const planning::PlanResult r = planning::planUavPath(v, s, g, 0.0, {}, static_cast<std::uint64_t>(i));
      ms.push_back(r.planning_time * 1e3);
      ok += r.status == planning::PlanStatus::kExact;
      ++total;
    }
    report(label, ms, ok, total);
  }
  {
    std::vector<double> ms;
    int ok = 0;
    const int edges = static_cast<int>(world.edges().size());
    const int nodes = static_cast<int>(world.nodes().size());
    for (int i = 0; i < count; ++i) {
      const auto& ed = world.edges()[static_cast<std::size_t>(rng.uniformInt(0, edges - 1))];
      const Vec2 a = world.nodes()[ed.a].position, c = world.nodes()[ed.b].position;
      const Vec2 d = (c - a).normalized(), n(d.y(), -d.x());
      const Vec2 p = 0.5 * (a + c) + n * 1.55;
      planning::RouteGoal goal;
      goal.node = static_cast<int>(rng.uniformInt(0, nodes - 1));
      const auto t0 = std::chrono::steady_clock::now();
      const planning::RouteResult r = planning::planVehicleRoute(
          world, {0, p.x(), p.y(), 0, std::atan2(d.y(), d.x())}, goal, static_cast<std::uint64_t>(i));
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      ok += r.ok();
    }
    report("car route (Dijkstra + Dubins)", ms, ok, count);
  }
  return 0;
}
