#pragma once
// Shared fixtures of the planning tests: the shipped world and mission, and an independent
// checker of timed paths built only on the geometry core (not on the planner's WorldValidity).

#include "hameritt/build_paths.h"
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hameritt/geometry/line_of_sight.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"
#include "../scenario/test_util.h"

namespace hameritt::planning::testing {

inline const scenario::World& world() { return scenario::testing::shippedWorld(); }

inline const scenario::Mission& shippedMission() {
  static const scenario::Mission m =
      scenario::loadMission(std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/mission.json");
  return m;
}

// Independent check of a timed path read as the simulator reads it (linear interpolation):
// every consecutive pair of samples is a segment that touches no raw obstacle box
// (OccluderIndex::clear, exact); positions every `step` metres with their interpolated times lie
// in the altitude band and outside every keep-out zone active then (Polygon::contains,
// TimeWindow::active). Returns "" or the first violation.
inline std::string independentCheck(const scenario::Trajectory& traj,
                                    const std::vector<scenario::KeepOutZone>& kozs, double zmin,
                                    double zmax, double step = 0.1) {
  using geometry::Vec3;
  const auto& occ = world().occluders();
  for (std::size_t i = 0; i < traj.size(); ++i) {
    const auto& p = traj[i];
    if (i > 0 && !(p.t > traj[i - 1].t)) return "time not increasing at " + std::to_string(i);
    if (i == 0) continue;
    const auto& q = traj[i - 1];
    const Vec3 a(q.x, q.y, q.z), b(p.x, p.y, p.z);
    if (!occ.clear(a, b)) return "segment " + std::to_string(i) + " hits an obstacle";
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
    for (int k = 0; k <= n; ++k) {
      const double u = static_cast<double>(k) / n;
      const Vec3 x = a + (b - a) * u;
      const double t = q.t + (p.t - q.t) * u;
      if (x.z() < zmin - 1e-9 || x.z() > zmax + 1e-9) return "outside the band at " + std::to_string(i);
      for (const auto& z : kozs) {
        const bool in_alt = (!z.alt_min || x.z() >= *z.alt_min) && (!z.alt_max || x.z() <= *z.alt_max);
        if (in_alt && z.window.active(t) && z.polygon.contains(x.head<2>())) {
          return "inside " + z.id + " at t = " + std::to_string(t);
        }
      }
    }
  }
  return "";
}

inline bool sameTrajectory(const scenario::Trajectory& a, const scenario::Trajectory& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].t != b[i].t || a[i].x != b[i].x || a[i].y != b[i].y || a[i].z != b[i].z ||
        a[i].yaw != b[i].yaw) {
      return false;
    }
  }
  return true;
}

}  // namespace hameritt::planning::testing
