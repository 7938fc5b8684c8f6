// The generator's use of the planning library: target routes from planVehicleRoute follow the
// route of interest's street nodes, and the perception-only path is re-verified independently.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>

#include "hameritt/planning/look_at.h"
#include "hameritt/planning/validity.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/trajectory.h"
#include "test_util.h"

using namespace hameritt::scenario;
using hameritt::geometry::Vec2;
using hameritt::geometry::Vec3;
using hameritt::scenario::testing::shippedConfig;
using hameritt::scenario::testing::shippedWorld;
namespace planning = hameritt::planning;

namespace {

// The street node at p, or -1.
int nodeAt(const World& w, const Vec2& p) {
  for (std::size_t i = 0; i < w.nodes().size(); ++i) {
    if ((w.nodes()[i].position - p).norm() < 1e-9) return static_cast<int>(i);
  }
  return -1;
}

bool adjacent(const World& w, int u, int v) {
  for (int e : w.adjacency()[static_cast<std::size_t>(u)]) {
    const auto& ed = w.edges()[static_cast<std::size_t>(e)];
    if ((ed.a == u && ed.b == v) || (ed.a == v && ed.b == u)) return true;
  }
  return false;
}

// Index of the first sample after `from` within `radius` of p, or -1.
int passes(const Trajectory& traj, int from, const Vec2& p, double radius) {
  for (int i = std::max(from, 0); i < static_cast<int>(traj.size()); ++i) {
    const auto& q = traj[static_cast<std::size_t>(i)];
    if ((Vec2(q.x, q.y) - p).norm() <= radius) return i;
  }
  return -1;
}

const ScenarioEntity* findEntity(const Scenario& s, const std::string& id) {
  for (const auto& e : s.sim.entities) {
    if (e.entity.id == id) return &e;
  }
  return nullptr;
}

}  // namespace

// The route of interest is a chain of adjacent street nodes, and every target car drives
// through those nodes in order (within a street width of each interior node, which the lane
// and its corner curve pass), ending on the route's last street short of its final node.
TEST(GeneratorPlanningTest, RouteSearchTargetsDriveTheRouteNodes) {
  const World& w = shippedWorld();
  const double street = w.params().street_width;
  int convoys = 0;
  for (std::uint64_t seed = 500; seed < 530; ++seed) {
    const Scenario s = generateScenario(w, shippedConfig(), ScenarioClass::kRouteSearch, seed);
    ASSERT_EQ(s.mission.routes.size(), 1u);
    const auto& poly = s.mission.routes[0].polyline;
    ASSERT_GE(poly.size(), 3u) << seed;
    std::vector<int> nodes;
    for (const auto& p : poly) nodes.push_back(nodeAt(w, p));
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      ASSERT_GE(nodes[i], 0) << seed << " vertex " << i << " is not a street node";
      if (i > 0) {
        EXPECT_TRUE(adjacent(w, nodes[i - 1], nodes[i])) << seed << " vertex " << i;
      }
    }
    EXPECT_EQ(std::set<int>(nodes.begin(), nodes.end()).size(), nodes.size()) << seed;
    convoys += s.mission.objective.targets.size() == 2;
    for (const auto& t : s.mission.objective.targets) {
      const ScenarioEntity* e = findEntity(s, t.id);
      ASSERT_NE(e, nullptr);
      ASSERT_GE(e->trajectory.size(), 2u);
      int at = 0;
      for (std::size_t k = 1; k + 1 < poly.size(); ++k) {
        at = passes(e->trajectory, at, poly[k], street);
        ASSERT_GE(at, 0) << seed << " " << t.id << " misses route node " << k;
      }
      // It stops on the last street: nearer the final node than the one before, not past it.
      const auto& end = e->trajectory.back();
      const Vec2 a = poly[poly.size() - 2], b = poly.back(), q(end.x, end.y);
      EXPECT_LT(hameritt::geometry::pointSegmentDistance(q, a, b), street / 2) << seed;
      EXPECT_LT((q - b).dot(b - a), 0.0) << seed << " " << t.id << " drives past the route";
    }
  }
  EXPECT_GT(convoys, 3) << "the convoy's second car should usually follow the same streets";
}

// Pursuit: the target waits at the kerb, pulls out at its departure time and drives on, with
// strictly increasing times; it leaves the slot no earlier than the AOI's deadline.
TEST(GeneratorPlanningTest, PursuitTargetWaitsThenDrives) {
  for (std::uint64_t seed = 600; seed < 620; ++seed) {
    const Scenario s =
        generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kPursuit, seed);
    const ScenarioEntity* e = findEntity(s, s.mission.objective.targets[0].id);
    ASSERT_NE(e, nullptr);
    const Trajectory& tr = e->trajectory;
    ASSERT_GE(tr.size(), 4u);
    for (std::size_t i = 1; i < tr.size(); ++i) EXPECT_GT(tr[i].t, tr[i - 1].t) << seed << " " << i;
    EXPECT_EQ(tr[0].t, 0.0);
    EXPECT_EQ(tr[1].t, *s.mission.aois[0].window.nlt) << seed;
    EXPECT_EQ(tr[0].x, tr[1].x);
    EXPECT_EQ(tr[0].y, tr[1].y);
    const double driven = (Vec2(tr.back().x, tr.back().y) - Vec2(tr[0].x, tr[0].y)).norm();
    EXPECT_GT(driven, 100.0) << seed << ": 6-12 street edges away";
  }
}

// The perception-only path, checked with the planning library's own tools but not by trusting
// the planner: times increase from the UAV start; the airborne part is valid against the
// mission's obstacles, band and keep-out zones; each target it lists projects into the named
// camera at some sample, where the target is at that time; an exact plan sees every target.
TEST(GeneratorPlanningTest, PerceptionPathIsVerified) {
  const World& w = shippedWorld();
  int exact = 0, total = 0;
  for (ScenarioClass c : {ScenarioClass::kAreaSearch, ScenarioClass::kRouteSearch,
                          ScenarioClass::kPursuit}) {
    for (std::uint64_t seed = 700; seed < 712; ++seed) {
      const Scenario s = generateScenario(w, shippedConfig(), c, seed);
      ASSERT_TRUE(s.sim.uav.perception_path.has_value());
      const PerceptionPath& pp = *s.sim.uav.perception_path;
      ++total;
      const Trajectory& tr = pp.trajectory;
      ASSERT_GE(tr.size(), 3u);
      EXPECT_EQ(tr[0].t, 0.0);
      EXPECT_EQ(tr[0].x, s.sim.uav.start.x);
      EXPECT_EQ(tr[0].y, s.sim.uav.start.y);
      for (std::size_t i = 1; i < tr.size(); ++i) {
        ASSERT_GT(tr[i].t, tr[i - 1].t) << seed << " " << i;
      }
      const planning::WorldValidity validity(w, s.mission,
                                             planning::validitySettingsFor(s.sim.uav));
      const Trajectory airborne(tr.begin() + 1, tr.end());
      EXPECT_EQ(validity.checkTrajectory(airborne, 0.25, 0.01), "") << toString(c) << " " << seed;
      const CameraSpec* cam = nullptr;
      for (const auto& k : s.sim.uav.cameras) {
        if (k.name == pp.camera) cam = &k;
      }
      ASSERT_NE(cam, nullptr) << pp.camera;
      std::set<std::string> targets;
      for (const auto& t : s.mission.objective.targets) targets.insert(t.id);
      for (const auto& id : pp.targets_seen) {
        ASSERT_TRUE(targets.count(id)) << id;
        const ScenarioEntity* e = findEntity(s, id);
        bool seen = false;
        for (const auto& q : tr) {
          auto box = e->entity.box;
          if (!e->trajectory.empty()) box = poseBox(box, sampleTrajectory(e->trajectory, q.t));
          if (planning::projectToImage(*cam, Vec3(q.x, q.y, q.z), q.yaw, box.center)) seen = true;
        }
        EXPECT_TRUE(seen) << toString(c) << " " << seed << " " << id;
      }
      if (pp.status == "exact") {
        ++exact;
        EXPECT_EQ(std::set<std::string>(pp.targets_seen.begin(), pp.targets_seen.end()), targets);
      }
    }
  }
  EXPECT_GT(exact, total / 2) << "most perception paths should see every target";
}

// The perception path survives the sim_config round trip byte for byte, and switching it off
// in the generator config leaves it out.
TEST(GeneratorPlanningTest, PerceptionPathRoundTripAndSwitch) {
  const Scenario s = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kPursuit, 42);
  ASSERT_TRUE(s.sim.uav.perception_path.has_value());
  const std::string text = simConfigJson(s.sim);
  const SimConfig back = simConfigFromJson(nlohmann::ordered_json::parse(text), "mem");
  ASSERT_TRUE(back.uav.perception_path.has_value());
  EXPECT_EQ(back.uav.perception_path->trajectory.size(),
            s.sim.uav.perception_path->trajectory.size());
  EXPECT_EQ(simConfigJson(back), text);
  GeneratorConfig off = shippedConfig();
  off.perception_paths = false;
  const Scenario t = generateScenario(shippedWorld(), off, ScenarioClass::kPursuit, 42);
  EXPECT_FALSE(t.sim.uav.perception_path.has_value());
  EXPECT_EQ(simConfigJson(t.sim).find("perception_path"), std::string::npos);
}
