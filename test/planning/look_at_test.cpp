#include "hameritt/build_paths.h"
#include "hameritt/planning/look_at.h"

#include <gtest/gtest.h>

#include "hameritt/scenario/sim_config_io.h"
#include "planning_test_util.h"

namespace hameritt::planning {
namespace {

using geometry::Vec2;
using geometry::Vec3;
using testing::independentCheck;
using testing::shippedMission;
using testing::world;

TEST(LookAtTest, ProjectionFollowsTheCameraModel) {
  scenario::CameraSpec cam;
  cam.width = 640;
  cam.height = 480;
  cam.hfov_deg = 90;
  cam.mount_rpy = Vec3(0, 0, 0);
  // Straight ahead (east, yaw 0) projects to the centre; left of the axis to u < 320.
  auto c = projectToImage(cam, Vec3(0, 0, 10), 0.0, Vec3(10, 0, 10));
  ASSERT_TRUE(c);
  EXPECT_NEAR(c->x(), 320, 1e-9);
  EXPECT_NEAR(c->y(), 240, 1e-9);
  auto l = projectToImage(cam, Vec3(0, 0, 10), 0.0, Vec3(10, 5, 10));
  ASSERT_TRUE(l);
  EXPECT_NEAR(l->x(), 320 - 320 * 0.5, 1e-9);
  EXPECT_FALSE(projectToImage(cam, Vec3(0, 0, 10), 0.0, Vec3(-10, 0, 10)));  // behind
  EXPECT_FALSE(projectToImage(cam, Vec3(0, 0, 10), geometry::kPi / 2, Vec3(10, 0, 10)));
  // Pitched 30 deg down: a point 30 deg below the axis is at the centre row.
  cam.mount_rpy = Vec3(0, 30, 0);
  auto d = projectToImage(cam, Vec3(0, 0, 10), 0.0, Vec3(10, 0, 10 - 10 * std::tan(geometry::kPi / 6)));
  ASSERT_TRUE(d);
  EXPECT_NEAR(d->y(), 240, 1e-9);
  // Down camera: the point below is at the centre.
  cam.mount_rpy = Vec3(0, 90, 0);
  auto n = projectToImage(cam, Vec3(3, 4, 30), 1.0, Vec3(3, 4, 0));
  ASSERT_TRUE(n);
  EXPECT_NEAR(n->x(), 320, 1e-6);
  EXPECT_NEAR(n->y(), 240, 1e-6);
}

TEST(LookAtTest, EveryEntityOfInterestIsVerifiedInViewAlongASafePath) {
  const scenario::SimConfig sim = scenario::loadSimConfig(
      std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/sim_config.json");
  std::vector<LookAtTarget> targets;
  for (const auto& se : sim.entities) {
    if (se.role == "target" || se.role == "confuser") {
      targets.push_back({se.entity.id, se.entity.box.center, {}});
    }
  }
  // Plus a few houses of the world (their own boxes do not occlude them).
  int houses = 0;
  for (std::size_t i = 0; i < world().entities().size() && houses < 3; i += 397) {
    const auto& e = world().entities()[i];
    if (e.cls == scenario::EntityClass::kHouse || e.cls == scenario::EntityClass::kCar) {
      targets.push_back({e.id, e.box.center, world().occludersOf(static_cast<int>(i))});
      ++houses;
    }
  }
  ASSERT_GE(targets.size(), 3u);
  const ValiditySettings vs = validitySettingsFor(sim.uav, 1.0);
  const WorldValidity v(world(), shippedMission(), vs);
  for (const auto& cam : sim.uav.cameras) {
    const Vec3 start(sim.uav.start.x, sim.uav.start.y, vs.altitude_min + 1);
    const LookAtResult r = planLookAtPath(v, cam, start, 0.0, targets, UavPlannerSettings{}, 9);
    if (cam.mount_rpy.y() < 60) {
      ASSERT_EQ(r.status, PlanStatus::kExact) << cam.name << ": " << r.message;
    } else {
      // A nadir camera cannot see a target under a vantage-denial zone reaching above the
      // band: such targets are reported unseen, the rest are still verified.
      for (const auto& id : r.unseen) {
        bool denied = false;
        for (const auto& t : targets) {
          if (t.id != id) continue;
          for (const auto& k : shippedMission().kozs) {
            denied |= k.polygon.distance(t.point.head<2>()) < 40.0 &&
                      (!k.alt_max || *k.alt_max >= vs.altitude_max);
          }
        }
        EXPECT_TRUE(denied) << id;
      }
    }
    ASSERT_EQ(r.viewpoints.size() + r.unseen.size(), targets.size());
    ASSERT_FALSE(r.viewpoints.empty());
    EXPECT_EQ(independentCheck(r.flight.path, shippedMission().kozs, vs.altitude_min,
                               vs.altitude_max), "");
    for (const auto& vp : r.viewpoints) {
      const LookAtTarget* t = nullptr;
      for (const auto& c : targets) {
        if (c.id == vp.target_id) t = &c;
      }
      ASSERT_NE(t, nullptr);
      // Re-project from the path's own sample at the viewpoint time.
      const auto s = scenario::sampleTrajectory(r.flight.path, vp.t);
      const Vec3 pos(s.x, s.y, s.z);
      const auto px = projectToImage(cam, pos, s.yaw, t->point);
      ASSERT_TRUE(px) << vp.target_id;
      EXPECT_GE(px->x(), 0);
      EXPECT_LE(px->x(), cam.width);
      EXPECT_TRUE(world().occluders().clear(cameraPosition(cam, pos, s.yaw), t->point,
                                            t->own_occluders))
          << vp.target_id;
    }
  }
}

TEST(LookAtTest, AnUnseeableTargetIsReported) {
  const ValiditySettings vs;
  const WorldValidity v(world(), shippedMission(), vs);
  scenario::CameraSpec cam;
  cam.mount_rpy = Vec3(0, 20, 0);
  // The centre of a house, its own boxes not ignored: always occluded.
  int house = -1;
  for (std::size_t i = 0; i < world().entities().size(); ++i) {
    if (world().entities()[i].cls == scenario::EntityClass::kHouse) {
      house = static_cast<int>(i);
      break;
    }
  }
  const std::vector<LookAtTarget> t{{"hidden", world().entities()[house].box.center, {}}};
  LookAtSettings look;
  look.candidates = 50;
  const LookAtResult r = planLookAtPath(v, cam, Vec3(0, 0, 30), 0.0, t, UavPlannerSettings{}, 1, look);
  EXPECT_EQ(r.status, PlanStatus::kNoSolution);
  ASSERT_EQ(r.unseen.size(), 1u);
  EXPECT_EQ(r.unseen[0], "hidden");
}

}  // namespace
}  // namespace hameritt::planning
