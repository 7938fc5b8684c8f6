#include "hameritt/planning/vehicle_routes.h"

#include <gtest/gtest.h>

#include <set>

#include "hameritt/geometry/segment.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/rng.h"
#include "planning_test_util.h"

namespace hameritt::planning {
namespace {

using geometry::Vec2;
using testing::world;

// A start pose in the right-hand lane, mid-way along edge e driven from a to b.
scenario::TrajectoryPoint laneStart(int e, bool forward, double t = 0) {
  const auto& ed = world().edges()[e];
  Vec2 a = world().nodes()[ed.a].position, b = world().nodes()[ed.b].position;
  if (!forward) std::swap(a, b);
  const Vec2 d = (b - a).normalized(), n(d.y(), -d.x());
  const Vec2 p = 0.5 * (a + b) + n * 1.55;
  return {t, p.x(), p.y(), 0.0, std::atan2(d.y(), d.x())};
}

// Independent street check: samples every 0.25 m lie within street_width / 2 of some
// centreline, the car's footprint overlaps no parked car, and away from intersections the car
// is right of the centreline it follows.
std::string streetCheck(const scenario::Trajectory& tr) {
  const auto& w = world();
  for (std::size_t i = 1; i < tr.size(); ++i) {
    const Vec2 a(tr[i - 1].x, tr[i - 1].y), b(tr[i].x, tr[i].y);
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.25)));
    for (int k = 0; k <= n; ++k) {
      const Vec2 p = a + (b - a) * (static_cast<double>(k) / n);
      double best = 1e9;
      int be = -1;
      for (std::size_t e = 0; e < w.edges().size(); ++e) {
        const double d = geometry::pointSegmentDistance(p, w.nodes()[w.edges()[e].a].position,
                                                        w.nodes()[w.edges()[e].b].position);
        if (d < best) {
          best = d;
          be = static_cast<int>(e);
        }
      }
      if (best > w.edges()[be].width / 2) return "off street at sample " + std::to_string(i);
      double node_d = 1e9;
      for (const auto& nd : w.nodes()) node_d = std::min(node_d, (nd.position - p).norm());
      if (node_d > 15.0) {
        const Vec2 ea = w.nodes()[w.edges()[be].a].position, eb = w.nodes()[w.edges()[be].b].position;
        const Vec2 heading(std::cos(tr[i].yaw), std::sin(tr[i].yaw));
        Vec2 dir = (eb - ea).normalized();
        if (dir.dot(heading) < 0) dir = -dir;
        const double side = geometry::cross2(dir, p - ea);  // > 0: left of the centreline
        if (side > -0.5) return "not driving on the right at sample " + std::to_string(i);
      }
    }
    geometry::OrientedBox car;
    car.center = geometry::Vec3(b.x(), b.y(), 0.8);
    car.size = geometry::Vec3(4.6, 1.9, 1.6);
    car.yaw = tr[i].yaw;
    for (int o : w.occluders().near(b, 4.0)) {
      if (geometry::footprintsOverlap(car, w.occluders().box(o))) return "hits a parked car";
    }
  }
  return "";
}

TEST(VehicleRoutesTest, TwoHundredSeededRoutesStayOnStreetsAndVary) {
  scenario::Rng rng(77);
  const int edges = static_cast<int>(world().edges().size());
  const int nodes = static_cast<int>(world().nodes().size());
  int ok = 0;
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    const int e = static_cast<int>(rng.uniformInt(0, edges - 1));
    const auto start = laneStart(e, rng.bernoulli(0.5), rng.uniform(0, 30));
    RouteGoal goal;
    goal.node = static_cast<int>(rng.uniformInt(0, nodes - 1));
    const RouteResult r = planVehicleRoute(world(), start, goal, seed);
    if (!r.ok()) {
      ADD_FAILURE() << "seed " << seed << ": " << toString(r.status) << ": " << r.message;
      continue;
    }
    ++ok;
    ASSERT_GE(r.trajectory.size(), 2u);
    EXPECT_EQ(r.trajectory.front().t, scenario::roundMilli(start.t));
    EXPECT_EQ(streetCheck(r.trajectory), "") << "seed " << seed;
    if (!r.nodes.empty()) {
      EXPECT_EQ(r.nodes.back(), goal.node);
    }
    double vmax = 0;
    for (std::size_t i = 1; i < r.trajectory.size(); ++i) {
      const auto& a = r.trajectory[i - 1];
      const auto& b = r.trajectory[i];
      ASSERT_GT(b.t, a.t);
      vmax = std::max(vmax, std::hypot(b.x - a.x, b.y - a.y) / (b.t - a.t));
    }
    EXPECT_LE(vmax, 10.0 * 1.02);
  }
  EXPECT_GE(ok, 198);
  // Same start and goal, different seeds: different routes; same seed: the same bytes.
  const auto start = laneStart(0, true);
  RouteGoal far;
  far.node = nodes - 1;
  std::set<std::vector<int>> routes;
  for (std::uint64_t seed = 0; seed < 40; ++seed) {
    const RouteResult r = planVehicleRoute(world(), start, far, seed);
    ASSERT_TRUE(r.ok()) << r.message;
    routes.insert(r.nodes);
  }
  EXPECT_GE(routes.size(), 4u);
  const RouteResult a = planVehicleRoute(world(), start, far, 3);
  const RouteResult b = planVehicleRoute(world(), start, far, 3);
  EXPECT_TRUE(testing::sameTrajectory(a.trajectory, b.trajectory));
}

TEST(VehicleRoutesTest, GoalPoseAndStatuses) {
  const auto start = laneStart(2, true);
  RouteGoal goal;
  goal.pose = laneStart(9, false);
  const RouteResult r = planVehicleRoute(world(), start, goal, 1);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(r.trajectory.back().x, goal.pose->x, 1e-3);
  EXPECT_NEAR(r.trajectory.back().y, goal.pose->y, 1e-3);
  EXPECT_EQ(streetCheck(r.trajectory), "");
  // Inside a house: not on a street.
  scenario::TrajectoryPoint bad = start;
  for (const auto& e : world().entities()) {
    if (e.cls == scenario::EntityClass::kHouse) {
      bad.x = e.box.center.x();
      bad.y = e.box.center.y();
      break;
    }
  }
  RouteGoal node0;
  node0.node = 0;
  EXPECT_EQ(planVehicleRoute(world(), bad, node0, 1).status, PlanStatus::kInvalidStart);
  RouteGoal missing;
  missing.node = 100000;
  EXPECT_EQ(planVehicleRoute(world(), start, missing, 1).status, PlanStatus::kInvalidGoal);
  SpeedProfile sp;
  sp.corner_speed = 20;
  try {
    planVehicleRoute(world(), start, node0, 1, sp);
    ADD_FAILURE() << "no error";
  } catch (const scenario::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "route.speed.corner_speed: expected at most cruise_speed (10), got 20");
  }
}

}  // namespace
}  // namespace hameritt::planning
