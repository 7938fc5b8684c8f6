#include "hameritt/planning/follow.h"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

#include "hameritt/geometry/oriented_box.h"
#include "planning_test_util.h"

namespace hameritt::planning {
namespace {

using geometry::Vec2;
using geometry::Vec3;
using testing::world;

// Independent of WorldValidity: the segment meets none of the world's raw obstacle boxes grown
// by `clearance` on every side.
bool clearOfEveryBox(const Vec3& a, const Vec3& b, double clearance) {
  const auto& occ = world().occluders();
  for (std::size_t i = 0; i < occ.size(); ++i) {
    geometry::OrientedBox o = occ.box(static_cast<int>(i));
    o.size += Vec3(2 * clearance, 2 * clearance, 2 * clearance);
    if (o.intersectsSegment(a, b)) return false;
  }
  return true;
}

Vec3 point(const scenario::TrajectoryPoint& p) { return {p.x, p.y, p.z}; }

// A path at 10 m/s that runs 1.05 m beside a house's long side and turns round its corner to run
// 1.05 m beside its short side, at half the house's height: clear of the planner's 1 m margin.
struct CornerPath {
  scenario::Trajectory path;
  double corner_t = 0;  // plan time at the corner
};

std::optional<CornerPath> cornerPath(const WorldValidity& v, const geometry::OrientedBox& b) {
  const double off = 1.05, c = std::cos(b.yaw), s = std::sin(b.yaw);
  const auto at = [&](double bx, double by) {
    return Vec3(b.center.x() + c * bx - s * by, b.center.y() + s * bx + c * by, b.center.z());
  };
  const double l = 0.5 * b.size.x() + off, w = 0.5 * b.size.y() + off;
  const std::vector<Vec3> pts{at(-l - 20, w), at(l, w), at(l, -w - 20)};
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    if (!v.obstacleSegmentClear(pts[i], pts[i + 1])) return std::nullopt;
  }
  CornerPath out;
  double t = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (i > 0) t += (pts[i] - pts[i - 1]).norm() / 10.0;
    if (i == 1) out.corner_t = t;
    out.path.push_back({t, pts[i].x(), pts[i].y(), pts[i].z(), 0.0});
  }
  return out;
}

TEST(FollowTest, TheCarrotIsPulledBackFromABuildingCornerAndOnlyThere) {
  ValiditySettings settings;  // margin 1 m
  const WorldValidity v(world(), std::vector<scenario::KeepOutZone>{}, settings);
  const auto& occ = world().occluders();
  int corners = 0, pulled = 0;
  for (std::size_t i = 0; i < occ.size() && corners < 12; ++i) {
    const geometry::OrientedBox& b = occ.box(static_cast<int>(i));
    if (b.size.z() < 4.0 || b.size.x() < 6.0 || b.size.y() < 6.0) continue;  // houses
    const auto cp = cornerPath(v, b);
    if (!cp) continue;
    ++corners;
    // Far from the corner the line to the full carrot runs along the side: not pulled back.
    const double far_t = cp->corner_t - 3.0;
    const Vec3 far = point(scenario::sampleTrajectory(cp->path, far_t));
    EXPECT_DOUBLE_EQ(clearCarrotTime(v, cp->path, far, far_t, 1.5, 0.5), far_t + 1.5);
    // 0.8 s before the corner the full carrot lies 7 m past it: the line cuts the house.
    const double near_t = cp->corner_t - 0.8;
    const Vec3 near = point(scenario::sampleTrajectory(cp->path, near_t));
    ASSERT_FALSE(
        clearOfEveryBox(near, point(scenario::sampleTrajectory(cp->path, near_t + 1.5)), 0.0));
    const double t = clearCarrotTime(v, cp->path, near, near_t, 1.5, 0.5);
    EXPECT_LT(t, near_t + 1.5);
    EXPECT_GE(t, near_t + 1.5 / 8 - 1e-12);
    if (t > near_t + 1.5 / 8 + 1e-9) {
      ++pulled;
      // A carrot chosen by the check is 0.5 m clear of every box (the fallback, 1/8 of the
      // lookahead, is taken whatever it meets).
      EXPECT_TRUE(clearOfEveryBox(near, point(scenario::sampleTrajectory(cp->path, t)), 0.5 - 1e-6))
          << "box " << i;
    }
  }
  EXPECT_GE(corners, 5);
  EXPECT_GE(pulled, corners / 2);
}

}  // namespace
}  // namespace hameritt::planning
