// Chase paths (planning::planChasePath), the perception-only flight of follow and track missions:
// judged on the generated scenarios' sim_configs with an independent reading of the path
// (linear interpolation, as the simulator plays it) against the target's scripted trajectory.
// Negative controls: a path that hovers where the chase caught up, and the chase played 10 s
// late, fail the same checks.
#include "hameritt/planning/chase.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hameritt/planning/look_at.h"
#include "planning_test_util.h"

namespace hameritt::planning {
namespace {

using geometry::Vec3;
using scenario::ScenarioClass;

const scenario::ScenarioEntity& phaseTarget(const scenario::Scenario& s) {
  const std::string id = s.mission.phases.back().targets.front();
  for (const auto& e : s.sim.entities) {
    if (e.entity.id == id) return e;
  }
  throw std::runtime_error("no target " + id);
}

struct Judged {
  int samples = 0, inside = 0, seen = 0;
  double max_speed = 0, max_climb = 0;
};

// From `from` to the time limit every 0.5 s: the UAV (path interpolated) inside the follow
// envelope (horizontal distance d* +- D from the target, behind it: not ahead of its heading by
// more than D; height h* +- H above it), and whether `camera` sees the target's box centre.
Judged judge(const scenario::Scenario& s, const scenario::Trajectory& path, double from,
             const scenario::CameraSpec& camera, double shift = 0.0) {
  const auto& target = phaseTarget(s);
  const auto& phase = s.mission.phases.back();
  const bool follow = phase.type == scenario::PhaseType::kFollow;
  Judged j;
  for (double t = from; t <= s.mission.time_limit; t += 0.5) {
    const auto u = scenario::sampleTrajectory(path, t - shift);
    const auto c = scenario::sampleTrajectory(target.trajectory, t);
    const Vec3 d(u.x - c.x, u.y - c.y, u.z - c.z);
    const double horizontal = d.head<2>().norm();
    const double ahead = d.x() * std::cos(c.yaw) + d.y() * std::sin(c.yaw);
    bool in = true;
    if (follow) {
      const auto& f = phase.follow;
      in = std::abs(horizontal - f.distance) <= f.distance_tolerance &&
           ahead <= f.distance_tolerance && std::abs(d.z() - f.height) <= f.height_tolerance;
    }
    const Vec3 centre(c.x, c.y, c.z + 0.5 * target.entity.box.size.z());
    const bool sees = projectToImage(camera, Vec3(u.x, u.y, u.z), u.yaw, centre).has_value() &&
                      testing::world().occluders().clear(
                          cameraPosition(camera, Vec3(u.x, u.y, u.z), u.yaw), centre, {});
    ++j.samples;
    j.inside += in;
    j.seen += sees;
  }
  for (std::size_t i = 1; i < path.size(); ++i) {
    const auto& a = path[i - 1];
    const auto& b = path[i];
    j.max_speed = std::max(j.max_speed, std::hypot(b.x - a.x, b.y - a.y) / (b.t - a.t));
    j.max_climb = std::max(j.max_climb, std::abs(b.z - a.z) / (b.t - a.t));
  }
  return j;
}

const scenario::CameraSpec& cameraOf(const scenario::Scenario& s, const std::string& name) {
  for (const auto& c : s.sim.uav.cameras) {
    if (c.name == name) return c;
  }
  throw std::runtime_error("no camera " + name);
}

// The first path time (after the climb) at which the UAV is within 2 m of its stand-off from
// the target (follow: d*; track: straight above), found independently of the planner's catch.
double caughtAt(const scenario::Scenario& s, const scenario::Trajectory& path) {
  const auto& phase = s.mission.phases.back();
  const double want = phase.type == scenario::PhaseType::kFollow ? phase.follow.distance : 0.0;
  for (const auto& k : path) {
    if (k.t <= path[1].t) continue;
    const auto c = scenario::sampleTrajectory(phaseTarget(s).trajectory, k.t);
    if (std::abs(std::hypot(k.x - c.x, k.y - c.y) - want) <= 2.0) return k.t;
  }
  return s.mission.time_limit;
}

TEST(ChaseTest, FollowAndTrackPerceptionPathsKeepTheTargetAndTheEnvelope) {
  const auto& cfg = scenario::testing::shippedConfig();
  int chases = 0, tried = 0, control_misses = 0, control_samples = 0, chase_misses = 0;
  for (ScenarioClass cls : {ScenarioClass::kFollow, ScenarioClass::kTrack}) {
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      ++tried;
      const scenario::Scenario s = scenario::generateScenario(testing::world(), cfg, cls, seed);
      SCOPED_TRACE(s.mission.scenario_id);
      ASSERT_TRUE(s.sim.uav.perception_path.has_value());
      const scenario::PerceptionPath& pp = *s.sim.uav.perception_path;
      if (pp.status != "chase") {
        // Why: the same chase, planned here.
        const WorldValidity validity(testing::world(), s.mission, validitySettingsFor(s.sim.uav));
        UavPlannerSettings settings;
        settings.speed.max_speed = s.sim.uav.max_speed;
        ChaseSettings chase;
        chase.height = 0.5 * (s.sim.uav.altitude_min + s.sim.uav.altitude_max);
        const auto& t = phaseTarget(s);
        const auto& u = s.sim.uav.start;
        const ChaseResult r =
            planChasePath(validity, cameraOf(s, "down"), Vec3(u.x, u.y, chase.height), 10.0,
                          s.mission.time_limit, t.trajectory, t.entity.box.size,
                          s.sim.uav.altitude_min, s.sim.uav.altitude_max, settings, chase);
        std::printf("%s: %s, no chase: %s\n", s.mission.scenario_id.c_str(), pp.status.c_str(),
                    r.message.c_str());
        continue;
      }
      ++chases;
      const bool follow = cls == ScenarioClass::kFollow;
      EXPECT_TRUE(pp.camera == "down" || (follow && pp.camera == "front")) << pp.camera;
      const auto& cam = cameraOf(s, pp.camera);
      // Safe: obstacles, band and keep-out zones, checked without the planner's validity.
      // (From the top of the climb: the first sample is the start on the ground.)
      const scenario::Trajectory flown(pp.trajectory.begin() + 1, pp.trajectory.end());
      EXPECT_EQ(testing::independentCheck(flown, s.mission.kozs, s.sim.uav.altitude_min,
                                          s.sim.uav.altitude_max),
                "");
      // Within the UAV's limits.
      const double caught = caughtAt(s, pp.trajectory);
      const Judged j = judge(s, pp.trajectory, caught, cam);
      EXPECT_LE(j.max_speed, s.sim.uav.max_speed + 1e-3);
      const double inside = static_cast<double>(j.inside) / j.samples;
      const double seen = static_cast<double>(j.seen) / j.samples;
      std::printf(
          "%s: caught at %.1f s of %.0f; from then %d samples, inside %.1f %%, seen %.1f "
          "%%, top speed %.2f m/s\n",
          s.mission.scenario_id.c_str(), caught, s.mission.time_limit, j.samples, 100 * inside,
          100 * seen, j.max_speed);
      // Caught up well before the end, then inside the envelope and seeing the target.
      EXPECT_LT(caught, s.mission.time_limit - 60.0);
      EXPECT_GE(inside, follow ? s.mission.phases.back().follow.min_inside_fraction : 1.0);
      EXPECT_GE(seen, 0.9);
      EXPECT_EQ(pp.targets_seen, std::vector<std::string>{phaseTarget(s).entity.id});
      // Negative controls: hovering where the chase caught up, and the chase 10 s late.
      scenario::Trajectory hover = {pp.trajectory.front(),
                                    scenario::sampleTrajectory(pp.trajectory, caught)};
      hover[1].t = caught;
      hover.push_back(hover[1]);
      hover[2].t = s.mission.time_limit;
      const Judged h = judge(s, hover, caught, cam);
      const Judged late = judge(s, pp.trajectory, caught, cam, 10.0);
      std::printf(
          "  controls: hovering: inside %.1f %%, seen %.1f %%; 10 s late: inside %.1f %%, "
          "seen %.1f %%\n",
          100.0 * h.inside / h.samples, 100.0 * h.seen / h.samples,
          100.0 * late.inside / late.samples, 100.0 * late.seen / late.samples);
      const int miss = follow ? j.samples - j.inside : j.samples - j.seen;
      control_misses += (follow ? h.samples - h.inside : h.samples - h.seen) +
                        (follow ? late.samples - late.inside : late.samples - late.seen);
      chase_misses += 2 * miss;
      control_samples += h.samples + late.samples;
    }
  }
  // The controls lose the target (or the envelope) far more often than the chase.
  std::printf("controls: %d of %d samples lost, the chase (counted twice): %d\n", control_misses,
              control_samples, chase_misses);
  EXPECT_GT(control_misses, 0.3 * control_samples);
  EXPECT_GT(control_misses, 10 * chase_misses);
  std::printf("chase paths: %d of %d follow and track scenarios\n", chases, tried);
  EXPECT_GE(chases, tried - 2);
}

TEST(ChaseTest, KeepOutZonesAreHeldAtOrCutTheChaseSayingWhen) {
  const auto& cfg = scenario::testing::shippedConfig();
  scenario::Scenario s =
      scenario::generateScenario(testing::world(), cfg, ScenarioClass::kTrack, 2);
  ASSERT_TRUE(s.sim.uav.perception_path && s.sim.uav.perception_path->status == "chase");
  const auto& path = s.sim.uav.perception_path->trajectory;
  const auto& target = phaseTarget(s);
  UavPlannerSettings settings;
  settings.speed.max_speed = s.sim.uav.max_speed;
  ChaseSettings chase;
  chase.height = path[1].z;
  auto plan = [&](const scenario::Mission& m) {
    const WorldValidity validity(testing::world(), m, validitySettingsFor(s.sim.uav));
    return planChasePath(validity, cameraOf(s, "down"), Vec3(path[1].x, path[1].y, path[1].z),
                         path[1].t, s.mission.time_limit, target.trajectory, target.entity.box.size,
                         s.sim.uav.altitude_min, s.sim.uav.altitude_max, settings, chase);
  };
  // Where the chase is at two thirds of its time: a 30 m square around it.
  const double tk = std::round(path.back().t * 2.0 / 3.0);
  const auto mid = scenario::sampleTrajectory(path, tk);
  scenario::KeepOutZone z;
  z.id = "koz_on_the_way";
  z.polygon = geometry::Polygon({{mid.x - 15, mid.y - 15},
                                 {mid.x + 15, mid.y - 15},
                                 {mid.x + 15, mid.y + 15},
                                 {mid.x - 15, mid.y + 15}});
  // Always active: the chase holds at its edge and goes on around it, never inside.
  scenario::Mission always = s.mission;
  always.kozs.push_back(z);
  const ChaseResult held = plan(always);
  EXPECT_EQ(held.status, PlanStatus::kExact) << held.message;
  EXPECT_EQ(testing::independentCheck(held.path, always.kozs, s.sim.uav.altitude_min,
                                      s.sim.uav.altitude_max),
            "");
  // Active from tk on, right over the UAV then: holding is no escape, the chase ends before tk.
  scenario::Mission sudden = s.mission;
  z.window.net = tk;
  sudden.kozs.push_back(z);
  const ChaseResult cut = plan(sudden);
  EXPECT_EQ(cut.status, PlanStatus::kNoSolution);
  EXPECT_NE(cut.message.find("keep-out zone"), std::string::npos) << cut.message;
  ASSERT_FALSE(cut.path.empty());
  EXPECT_LT(cut.path.back().t, tk + 1e-9);
  EXPECT_GT(cut.path.back().t, tk - 2.0);
  // Without the zone the same chase runs to the end (the control).
  const ChaseResult ok = plan(s.mission);
  EXPECT_EQ(ok.status, PlanStatus::kExact) << ok.message;
  EXPECT_DOUBLE_EQ(ok.path.back().t, s.mission.time_limit);
}

TEST(ChaseTest, BadSettingsNameTheField) {
  ChaseSettings c;
  c.behind = -1;
  try {
    c.validate();
    FAIL() << "no error";
  } catch (const scenario::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("chase.behind"), std::string::npos) << e.what();
  }
  c = ChaseSettings();
  c.step = 0;
  EXPECT_THROW(c.validate(), scenario::ConfigError);
}

}  // namespace
}  // namespace hameritt::planning
