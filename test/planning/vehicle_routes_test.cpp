#include "hameritt/planning/vehicle_routes.h"

#include <gtest/gtest.h>

#include <cstdio>
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
std::string streetCheck(const scenario::Trajectory& tr,
                        const scenario::World& w = testing::world()) {
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

// A route in the city's right-hand lane of edge e (driven a -> b) to its end node b: it stops in
// its lane corner_clearance before the node, as mission cars did.
RouteResult cityRouteToEnd(int e, const RouteSettings& rs) {
  const auto& w = scenario::testing::shippedCityWorld();
  const auto& ed = w.edges()[static_cast<std::size_t>(e)];
  const Vec2 a = w.nodes()[ed.a].position, b = w.nodes()[ed.b].position;
  const Vec2 d = (b - a).normalized(), n(d.y(), -d.x());
  const Vec2 p = a + d * 20.0 + n * rs.lane_offset;
  RouteGoal g;
  g.node = ed.b;
  return planVehicleRoute(w, {0.0, p.x(), p.y(), 0.0, std::atan2(d.y(), d.x())}, g, 3, {}, rs);
}

// Independent figures of a stop on edge e (driven a -> b): the front's distance before the
// crossing streets' box (their half width and the crosswalk), the right side's distance from the
// kerb, the largest braking between samples 1 m apart or more, the car inside the carriageway.
struct StopFigures {
  double before_box, kerb_gap, max_decel;
};
StopFigures stopFigures(int e, const scenario::Trajectory& tr, double sidewalk, double length,
                        double width) {
  const auto& w = scenario::testing::shippedCityWorld();
  const auto& ed = w.edges()[static_cast<std::size_t>(e)];
  const Vec2 a = w.nodes()[ed.a].position, b = w.nodes()[ed.b].position;
  const Vec2 d = (b - a).normalized(), n(d.y(), -d.x());
  double box = 0.0;
  for (int ei : w.adjacency()[static_cast<std::size_t>(ed.b)]) {
    if (ei != e)
      box = std::max(box, 0.5 * w.edges()[static_cast<std::size_t>(ei)].width + sidewalk);
  }
  const Vec2 end(tr.back().x, tr.back().y);
  StopFigures f;
  f.before_box = (b - a).norm() - box - ((end - a).dot(d) + 0.5 * length);
  f.kerb_gap = 0.5 * ed.width - ((end - a).dot(n) + 0.5 * width);
  f.max_decel = 0.0;
  // Speeds over spans of at least 1 m, compared between consecutive spans.
  std::vector<std::pair<double, double>> tv;  // (mid time, speed)
  std::size_t i = 0;
  while (i + 1 < tr.size()) {
    std::size_t j = i + 1;
    double len = 0.0;
    while (j < tr.size()) {
      len = std::hypot(tr[j].x - tr[i].x, tr[j].y - tr[i].y);
      if (len >= 1.0) break;
      ++j;
    }
    if (j >= tr.size()) break;
    tv.push_back({0.5 * (tr[i].t + tr[j].t), len / (tr[j].t - tr[i].t)});
    i = j;
  }
  for (std::size_t k = 1; k < tv.size(); ++k) {
    f.max_decel =
        std::max(f.max_decel, (tv[k - 1].second - tv[k].second) / (tv[k].first - tv[k - 1].first));
  }
  return f;
}

TEST(VehicleRoutesTest, CityRouteEndsPullOverToTheKerbBeforeTheIntersection) {
  const auto& w = scenario::testing::shippedCityWorld();
  const double arterial = w.params().city.arterial_width;
  RouteSettings rs;
  rs.lane_offset = 0.5 * w.params().street_width - 3.45;
  rs.corner_clearance = 0.5 * w.params().street_width + 1.0;
  KerbStop k;
  k.sidewalk_width = w.params().city.sidewalk_width;
  k.kerb_street_width = arterial;
  int arterial_stops = 0, local_stops = 0;
  for (std::size_t e = 0; e < w.edges().size(); ++e) {
    const auto& ed = w.edges()[e];
    if (w.adjacency()[static_cast<std::size_t>(ed.b)].size() < 3) continue;
    const double len = (w.nodes()[ed.b].position - w.nodes()[ed.a].position).norm();
    if (len < 100.0) continue;
    const RouteResult r = cityRouteToEnd(static_cast<int>(e), rs);
    if (!r.ok()) continue;
    const KerbStopResult st = stopAtKerb(w, r.trajectory, k, rs);
    SCOPED_TRACE("edge " + std::to_string(e));
    ASSERT_TRUE(st.ok);
    ASSERT_TRUE(st.changed);
    const bool wide = ed.width >= arterial - 1e-9;
    EXPECT_EQ(st.at_kerb, wide);
    // The route as planned: it stops inside the crossing street's box, in its lane.
    const StopFigures before = stopFigures(static_cast<int>(e), r.trajectory, k.sidewalk_width,
                                           rs.vehicle_length, rs.vehicle_width);
    EXPECT_LT(before.before_box, 0.0);
    const StopFigures f = stopFigures(static_cast<int>(e), st.trajectory, k.sidewalk_width,
                                      rs.vehicle_length, rs.vehicle_width);
    EXPECT_NEAR(f.before_box, k.stop_back, 0.01);
    EXPECT_LE(f.max_decel, k.max_decel + 0.1);
    EXPECT_GE(f.kerb_gap, k.kerb_gap - 0.01);
    if (wide) {
      // Out of both lanes that the traffic drives (3.5 m each, right of the centreline).
      EXPECT_NEAR(f.kerb_gap, k.kerb_gap, 0.01);
      EXPECT_GE(0.5 * ed.width - f.kerb_gap - rs.vehicle_width, 7.0);
      ++arterial_stops;
    } else {
      EXPECT_GT(f.kerb_gap, 2.0);  // in its lane
      ++local_stops;
    }
    EXPECT_EQ(streetCheck(st.trajectory, w), "");
    for (std::size_t i = 1; i < st.trajectory.size(); ++i) {
      ASSERT_GT(st.trajectory[i].t, st.trajectory[i - 1].t);
    }
    // The same route up to where the blend starts.
    ASSERT_GT(st.trajectory.size(), 3u);
    EXPECT_EQ(st.trajectory[1].x, r.trajectory[1].x);
    EXPECT_EQ(st.trajectory[1].t, r.trajectory[1].t);
    // A car that already stops clear: unchanged.
    EXPECT_FALSE(stopAtKerb(w, st.trajectory, k, rs).changed);
    // Deterministic.
    const KerbStopResult again = stopAtKerb(w, r.trajectory, k, rs);
    ASSERT_EQ(again.trajectory.size(), st.trajectory.size());
    for (std::size_t i = 0; i < again.trajectory.size(); ++i) {
      EXPECT_EQ(again.trajectory[i].t, st.trajectory[i].t);
      EXPECT_EQ(again.trajectory[i].y, st.trajectory[i].y);
    }
    // A car ahead stopped where this one stops: it stops follow_gap behind.
    KerbStop behind = k;
    behind.behind = st.trajectory.back();
    const KerbStopResult follow = stopAtKerb(w, r.trajectory, behind, rs);
    if (follow.ok) {
      const auto& p = follow.trajectory.back();
      EXPECT_NEAR(std::hypot(p.x - st.trajectory.back().x, p.y - st.trajectory.back().y),
                  k.follow_gap, 0.01);
    }
    // Negative control: no kerb on any street; the car stops in its lane, which the kerb
    // check above then flags on the arterials.
    KerbStop lane = k;
    lane.kerb_street_width = 100.0;
    const KerbStopResult in_lane = stopAtKerb(w, r.trajectory, lane, rs);
    EXPECT_FALSE(in_lane.at_kerb);
    if (wide) {
      EXPECT_GT(stopFigures(static_cast<int>(e), in_lane.trajectory, k.sidewalk_width,
                            rs.vehicle_length, rs.vehicle_width)
                    .kerb_gap,
                k.kerb_gap + 2.0);
    }
  }
  EXPECT_GE(arterial_stops, 3);
  EXPECT_GE(local_stops, 3);
  std::printf("kerb stops: %d on arterials, %d in the lane of local streets\n", arterial_stops,
              local_stops);
  KerbStop bad = k;
  bad.max_decel = 1.0;
  EXPECT_EQ(scenario::testing::messageOf([&] { stopAtKerb(w, {}, bad); }),
            "kerb_stop.max_decel: expected m/s^2 in [decel, 10], got 1");
}

}  // namespace
}  // namespace hameritt::planning
