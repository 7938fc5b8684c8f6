#include "hameritt/planning/uav_planner.h"

#include <gtest/gtest.h>

#include <thread>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/rng.h"
#include "planning_test_util.h"

namespace hameritt::planning {
namespace {

using geometry::Vec2;
using geometry::Vec3;
using scenario::KeepOutZone;
using testing::independentCheck;
using testing::sameTrajectory;
using testing::shippedMission;
using testing::world;

KeepOutZone rectKoz(const std::string& id, Vec2 lo, Vec2 hi, std::optional<double> net = {},
                    std::optional<double> nlt = {}) {
  KeepOutZone k;
  k.id = id;
  k.purpose = "restricted";
  k.polygon = geometry::rectangle(lo, hi);
  k.window.net = net;
  k.window.nlt = nlt;
  return k;
}

// A point far (independently of the planner) from every obstacle and zone footprint.
bool clearPoint(const Vec3& p, const std::vector<KeepOutZone>& kozs, double r) {
  if (!world().occluders().near(p.head<2>(), r).empty()) {
    for (int i : world().occluders().near(p.head<2>(), r)) {
      if (world().occluders().box(i).maxZ() + r >= p.z()) return false;
    }
  }
  for (const auto& k : kozs) {
    if (k.polygon.distance(p.head<2>()) <= r) return false;
  }
  return true;
}

bool endsAt(const scenario::Trajectory& t, const Vec3& p) {
  const auto& b = t.back();
  return std::abs(b.x - p.x()) < 1e-3 && std::abs(b.y - p.y()) < 1e-3 && std::abs(b.z - p.z()) < 1e-3;
}

TEST(UavPlannerTest, HundredsOfSeededProblemsAreSafeByAnIndependentCheck) {
  // Shipped KOZs plus three random ones with random windows per problem, a low band so that
  // houses and trees are in the way.
  const auto& shipped = shippedMission().kozs;
  scenario::Rng rng(20240601);
  const auto b = world().bounds();
  int problems = 0, exact = 0, nontrivial = 0;
  for (int n = 0; problems < 300 && n < 5000; ++n) {
    std::vector<KeepOutZone> kozs = shipped;
    for (int k = 0; k < 3; ++k) {
      const Vec2 c(rng.uniform(b.min.x(), b.max.x()), rng.uniform(b.min.y(), b.max.y()));
      const Vec2 h(rng.uniform(15, 60), rng.uniform(15, 60));
      KeepOutZone z = rectKoz("rand_" + std::to_string(k), c - h, c + h);
      if (rng.bernoulli(0.5)) {
        z.window.net = rng.uniform(0, 60);
        z.window.nlt = *z.window.net + rng.uniform(5, 60);
      }
      if (rng.bernoulli(0.5)) z.alt_max = rng.uniform(10, 30);
      kozs.push_back(z);
    }
    ValiditySettings vs;
    vs.altitude_min = 3.0;
    vs.altitude_max = 30.0;
    vs.margin = 1.0;
    auto sample = [&] {
      return Vec3(rng.uniform(b.min.x() + 5, b.max.x() - 5), rng.uniform(b.min.y() + 5, b.max.y() - 5),
                  rng.uniform(4, 29));
    };
    const Vec3 s = sample(), g = sample();
    if (!clearPoint(s, kozs, 2.0) || !clearPoint(g, kozs, 2.0)) continue;
    ++problems;
    const WorldValidity v(world(), kozs, vs);
    UavPlannerSettings st;
    const PlanResult r = planUavPath(v, s, g, 0.0, st, static_cast<std::uint64_t>(n));
    if (r.status != PlanStatus::kExact) {
      ADD_FAILURE() << "problem " << n << ": " << toString(r.status) << ": " << r.message;
      continue;
    }
    ++exact;
    nontrivial += r.iterations > 0;
    ASSERT_GE(r.path.size(), 2u);
    EXPECT_TRUE(endsAt(r.path, g));
    EXPECT_EQ(r.path.front().x, scenario::roundMilli(s.x()));
    EXPECT_EQ(independentCheck(r.path, kozs, vs.altitude_min, vs.altitude_max), "")
        << "problem " << n;
  }
  ASSERT_EQ(problems, 300);
  // Success rate on solvable problems (start and goal 2 m clear of everything): >= 99%.
  EXPECT_GE(exact, 297) << exact << "/" << problems;
  EXPECT_GT(nontrivial, 100);  // most problems needed the sampling planner, not a straight line
}

TEST(UavPlannerTest, SameSeedSamePathOnAnyThreadAndDifferentSeedsDiffer) {
  ValiditySettings vs;
  vs.altitude_min = 3;
  vs.altitude_max = 25;
  const WorldValidity v(world(), shippedMission().kozs, vs);
  const Vec3 s(-400, -300, 5), g(380, 320, 6);
  UavPlannerSettings st;
  const PlanResult a1 = planUavPath(v, s, g, 0.0, st, 11);
  const PlanResult b1 = planUavPath(v, s, g, 0.0, st, 12);
  ASSERT_EQ(a1.status, PlanStatus::kExact) << a1.message;
  ASSERT_EQ(b1.status, PlanStatus::kExact) << b1.message;
  EXPECT_FALSE(sameTrajectory(a1.path, b1.path));
  // Unrelated plans in between must not change anything.
  planUavPath(v, Vec3(0, 0, 10), Vec3(100, 100, 12), 0.0, st, 99);
  const PlanResult a2 = planUavPath(v, s, g, 0.0, st, 11);
  EXPECT_TRUE(sameTrajectory(a1.path, a2.path));
  EXPECT_EQ(a1.iterations, a2.iterations);
  PlanResult ta, tb;
  std::thread t1([&] { ta = planUavPath(v, s, g, 0.0, st, 11); });
  std::thread t2([&] { tb = planUavPath(v, s, g, 0.0, st, 12); });
  t1.join();
  t2.join();
  EXPECT_TRUE(sameTrajectory(ta.path, a1.path));
  EXPECT_TRUE(sameTrajectory(tb.path, b1.path));
  // RRT* is deterministic too.
  st.algorithm = UavAlgorithm::kRrtStar;
  st.rrtstar_iterations = 600;
  const PlanResult r1 = planUavPath(v, s, g, 0.0, st, 5);
  const PlanResult r2 = planUavPath(v, s, g, 0.0, st, 5);
  ASSERT_EQ(r1.status, PlanStatus::kExact) << r1.message;
  EXPECT_TRUE(sameTrajectory(r1.path, r2.path));
  EXPECT_EQ(independentCheck(r1.path, shippedMission().kozs, vs.altitude_min, vs.altitude_max), "");
}

// A 400 m wall of a keep-out zone (all altitudes) across the straight line, active only in
// [60, 90] s.
struct WallCase {
  std::vector<KeepOutZone> kozs{rectKoz("wall", Vec2(-2, -200), Vec2(2, 200), 60.0, 90.0)};
  ValiditySettings vs;
  Vec3 s{-100, 0, 0}, g{100, 0, 0};
  double clearZ() {
    // Above every obstacle near the line, inside the band.
    double top = 0;
    for (int i : world().occluders().candidates(geometry::Aabb2{Vec2(-130, -230), Vec2(130, 230)})) {
      top = std::max(top, world().occluders().box(i).maxZ());
    }
    return top + 3.0;
  }
  WallCase() {
    const double z = clearZ();
    vs.altitude_min = z - 1;
    vs.altitude_max = z + 20;
    s.z() = g.z() = z;
  }
  bool crossesWall(const scenario::Trajectory& t) const {
    for (const auto& p : t) {
      if (kozs[0].polygon.contains(Vec2(p.x, p.y))) return true;
    }
    return false;
  }
};

TEST(UavPlannerTest, KozIsCheckedAtTheTimeThePathReachesIt) {
  WallCase w;
  const WorldValidity v(world(), w.kozs, w.vs);
  UavPlannerSettings st;
  // Leaving at t = 0 the UAV passes the wall near t = 10 s, long before it activates.
  const PlanResult early = planUavPath(v, w.s, w.g, 0.0, st, 3);
  ASSERT_EQ(early.status, PlanStatus::kExact) << early.message;
  EXPECT_TRUE(w.crossesWall(early.path));
  EXPECT_LT(early.length, 200.5);
  EXPECT_EQ(independentCheck(early.path, w.kozs, w.vs.altitude_min, w.vs.altitude_max), "");
  // Leaving at t = 60 it would arrive near t = 70: it must go around.
  const PlanResult late = planUavPath(v, w.s, w.g, 60.0, st, 3);
  ASSERT_EQ(late.status, PlanStatus::kExact) << late.message;
  EXPECT_GT(late.length, 350.0);
  EXPECT_EQ(independentCheck(late.path, w.kozs, w.vs.altitude_min, w.vs.altitude_max), "");
  for (const auto& p : late.path) {
    if (w.kozs[0].polygon.contains(Vec2(p.x, p.y))) {
      EXPECT_FALSE(p.t >= 60 && p.t <= 90) << p.t;
    }
  }
  // Leaving at t = 85 it arrives after the window closed: straight through again.
  const PlanResult after = planUavPath(v, w.s, w.g, 85.0, st, 3);
  ASSERT_EQ(after.status, PlanStatus::kExact) << after.message;
  EXPECT_TRUE(w.crossesWall(after.path));
  EXPECT_GT(after.path[after.path.size() / 2].t, 90.0);
  // The straight early path replayed 60 s later is rejected by the checker.
  scenario::Trajectory shifted = early.path;
  for (auto& p : shifted) p.t += 60.0;
  EXPECT_NE(v.checkTrajectory(shifted), "");
  EXPECT_NE(independentCheck(shifted, w.kozs, w.vs.altitude_min, w.vs.altitude_max), "");
}

TEST(UavPlannerTest, StatusOutcomes) {
  ValiditySettings vs;
  vs.altitude_min = 1;
  vs.altitude_max = 40;
  // Invalid start: inside a house.
  int house = -1;
  for (std::size_t i = 0; i < world().entities().size(); ++i) {
    if (world().entities()[i].cls == scenario::EntityClass::kHouse) {
      house = static_cast<int>(i);
      break;
    }
  }
  ASSERT_GE(house, 0);
  const Vec3 in_house = world().entities()[house].box.center;
  const Vec3 open_goal(0, 0, 35);
  {
    const WorldValidity v(world(), std::vector<KeepOutZone>{}, vs);
    const PlanResult r = planUavPath(v, in_house, open_goal, 0, UavPlannerSettings{}, 1);
    EXPECT_EQ(r.status, PlanStatus::kInvalidStart);
    EXPECT_NE(r.message.find(world().entities()[house].id), std::string::npos) << r.message;
    EXPECT_TRUE(r.path.empty());
  }
  // Invalid goal: inside an active keep-out zone (and one that activates after arrival).
  {
    const std::vector<KeepOutZone> kozs{rectKoz("k", Vec2(-20, -20), Vec2(20, 20)),
                                        rectKoz("later", Vec2(200, 200), Vec2(240, 240), 500.0, 600.0)};
    const WorldValidity v(world(), kozs, vs);
    EXPECT_EQ(planUavPath(v, Vec3(-300, -300, 35), open_goal, 0, UavPlannerSettings{}, 1).status,
              PlanStatus::kInvalidGoal);
    EXPECT_EQ(planUavPath(v, Vec3(-300, -300, 35), Vec3(220, 220, 35), 0, UavPlannerSettings{}, 1)
                  .status,
              PlanStatus::kInvalidGoal);
    // Starting inside a zone that is not yet active is fine.
    EXPECT_EQ(planUavPath(v, Vec3(220, 220, 35), Vec3(300, 300, 35), 0, UavPlannerSettings{}, 1)
                  .status,
              PlanStatus::kExact);
  }
  // Boxed in: four zone walls around the goal, every altitude.
  {
    const std::vector<KeepOutZone> kozs{rectKoz("w", Vec2(-60, -60), Vec2(-50, 60)),
                                        rectKoz("e", Vec2(50, -60), Vec2(60, 60)),
                                        rectKoz("s", Vec2(-60, -60), Vec2(60, -50)),
                                        rectKoz("n", Vec2(-60, 50), Vec2(60, 60))};
    const WorldValidity v(world(), kozs, vs);
    UavPlannerSettings st;
    st.max_iterations = 3000;
    const PlanResult r = planUavPath(v, Vec3(-300, -300, 35), open_goal, 0, st, 1);
    EXPECT_EQ(r.status, PlanStatus::kNoSolution) << r.message;
    EXPECT_TRUE(r.path.empty());
    EXPECT_GT(r.iterations, 0);
    EXPECT_LE(r.iterations, 3000);
    st.accept_approximate = true;
    const PlanResult ap = planUavPath(v, Vec3(-300, -300, 35), open_goal, 0, st, 1);
    EXPECT_EQ(ap.status, PlanStatus::kApproximate) << ap.message;
    EXPECT_EQ(independentCheck(ap.path, kozs, vs.altitude_min, vs.altitude_max), "");
  }
}

TEST(UavPlannerTest, SettingsAreValidatedWithTheFieldNamed) {
  const WorldValidity v(world(), std::vector<KeepOutZone>{}, ValiditySettings{});
  auto err = [&](UavPlannerSettings st) -> std::string {
    try {
      planUavPath(v, Vec3(0, 0, 30), Vec3(10, 0, 30), 0, st, 1);
    } catch (const scenario::ConfigError& e) {
      return e.what();
    }
    return "";
  };
  UavPlannerSettings st;
  EXPECT_EQ(err(st), "");
  st.range = -1;
  EXPECT_EQ(err(st), "planning.range: expected a positive finite distance in metres, got -1");
  st = UavPlannerSettings{};
  st.goal_bias = 1.5;
  EXPECT_EQ(err(st), "planning.goal_bias: expected a probability in [0, 1], got 1.5");
  st = UavPlannerSettings{};
  st.time_limit = 0;
  EXPECT_EQ(err(st), "planning.time_limit: expected seconds in (0, 3600], got 0");
  st = UavPlannerSettings{};
  st.speed.max_speed = 0;
  EXPECT_NE(err(st).find("planning.speed.max_speed"), std::string::npos);
  ValiditySettings vs;
  vs.margin = 0;
  EXPECT_THROW(WorldValidity(world(), std::vector<KeepOutZone>{}, vs), scenario::ConfigError);
  try {
    vs.validate();
  } catch (const scenario::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "planning.margin: expected metres in [0.1, 20], got 0");
  }
  vs = ValiditySettings{};
  vs.altitude_max = vs.altitude_min;
  EXPECT_THROW(vs.validate(), scenario::ConfigError);
}

TEST(UavPlannerTest, SparseWaypointsBecomeOneSafeTimedFlight) {
  ValiditySettings vs;
  vs.altitude_min = 3;
  vs.altitude_max = 30;
  const auto& kozs = shippedMission().kozs;
  const WorldValidity v(world(), kozs, vs);
  std::vector<Vec3> wps;
  scenario::Rng rng(4);
  while (wps.size() < 4) {
    const Vec3 p(rng.uniform(-450, 450), rng.uniform(-450, 450), rng.uniform(5, 28));
    if (clearPoint(p, kozs, 2.0)) wps.push_back(p);
  }
  const PlanResult r = planUavWaypoints(v, wps, 5.0, UavPlannerSettings{}, 8);
  ASSERT_EQ(r.status, PlanStatus::kExact) << r.message;
  EXPECT_EQ(r.path.front().t, 5.0);
  for (const auto& w : wps) {
    bool hit = false;
    for (const auto& p : r.path) hit |= (Vec3(p.x, p.y, p.z) - w).norm() < 2e-3;
    EXPECT_TRUE(hit);
  }
  EXPECT_EQ(independentCheck(r.path, kozs, vs.altitude_min, vs.altitude_max), "");
  EXPECT_EQ(v.checkTrajectory(r.path, 0.25, 2e-3), "");
  // Speeds respect the limits (with the 1e-3 rounding).
  for (std::size_t i = 1; i < r.path.size(); ++i) {
    const auto& a = r.path[i - 1];
    const auto& b = r.path[i];
    const double dt = b.t - a.t;
    EXPECT_LE(std::hypot(b.x - a.x, b.y - a.y) / dt, 12.0 * 1.01 + 0.01 / dt);
    EXPECT_LE((b.z - a.z) / dt, 3.0 * 1.01 + 0.01 / dt);
  }
}

}  // namespace
}  // namespace hameritt::planning
