#include "hameritt/adk/coverage.h"

#include <gtest/gtest.h>

#include <cmath>

#include "adk_test_util.h"
#include "hameritt/adk/intervals.h"

namespace hameritt::adk {
namespace {

using namespace testing;  // NOLINT

Eigen::Isometry3d basePose(const Vec3& p, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = p;
  T.linear() = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
  return T;
}

scenario::CameraSpec camera(double pitch_deg, double hfov_deg) {
  scenario::CameraSpec c;
  c.name = "cam";
  c.mount_rpy = Vec3(0, pitch_deg, 0);
  c.width = 640;
  c.height = 480;
  c.hfov_deg = hfov_deg;
  return c;
}

TEST(Camera, IntrinsicsFromHfovAndOpticalPose) {
  const CameraIntrinsics k = intrinsicsFromHfov(640, 480, 90.0);
  EXPECT_NEAR(k.fx, 320.0, 1e-12);
  EXPECT_EQ(k.fx, k.fy);
  EXPECT_EQ(k.cx, 319.5);
  EXPECT_EQ(k.cy, 239.5);
  EXPECT_THROW(intrinsicsFromHfov(640, 480, 180.0), InputError);
  EXPECT_THROW(intrinsicsFromHfov(0, 480, 60.0), InputError);
  // Level camera on a UAV heading north (+y): the optical z looks north, x east, y down.
  const auto T = opticalPose(basePose(Vec3(1, 2, 3), geometry::kPi / 2), camera(0, 90));
  EXPECT_TRUE(T.linear().col(2).isApprox(Vec3(0, 1, 0), 1e-12));
  EXPECT_TRUE(T.linear().col(0).isApprox(Vec3(1, 0, 0), 1e-12));
  EXPECT_TRUE(T.linear().col(1).isApprox(Vec3(0, 0, -1), 1e-12));
  // Pitch 90 (the down camera): z down; image "up" (-y) points where the UAV heads.
  const auto D = opticalPose(basePose(Vec3(0, 0, 10), 0.0), camera(90, 60));
  EXPECT_TRUE(D.linear().col(2).isApprox(Vec3(0, 0, -1), 1e-12));
  EXPECT_TRUE((-D.linear().col(1)).isApprox(Vec3(1, 0, 0), 1e-12));
}

TEST(GroundFootprint, DownCameraSeesARectangle) {
  const double h = 40.0;
  const auto cam = camera(90, 60);
  const auto k = intrinsicsFromHfov(cam.width, cam.height, cam.hfov_deg);
  const auto fp = groundFootprint(k, opticalPose(basePose(Vec3(5, -7, h), 0.3), cam));
  // Outer pixel edges: half-width h tan(30 deg), half-height that times 480 / 640.
  const double hw = h * std::tan(geometry::degToRad(30.0)), hh = hw * 480.0 / 640.0;
  EXPECT_NEAR(fp.area(), 4 * hw * hh, 1e-6);
  EXPECT_GT(fp.signedArea(), 0.0);
  EXPECT_NEAR((fp.centroid() - Vec2(5, -7)).norm(), 0.0, 1e-9);
  // The long side lies across the heading (the image's width is the body's left-right).
  const Vec2 across(-std::sin(0.3), std::cos(0.3));
  EXPECT_TRUE(fp.contains(Vec2(5, -7) + across * (hw - 0.01)));
  EXPECT_FALSE(fp.contains(Vec2(5, -7) + across * (hw + 0.01)));
}

TEST(GroundFootprint, HorizonIsClippedToMaxRangeAndNothingBelowOrUp) {
  const auto cam = camera(10, 94);
  const auto k = intrinsicsFromHfov(cam.width, cam.height, cam.hfov_deg);
  const auto T = opticalPose(basePose(Vec3(0, 0, 40), 0.0), cam);
  const auto fp = groundFootprint(k, T, 150.0);
  ASSERT_GE(fp.size(), 3u);
  double far = 0.0, near = 1e9;
  for (const auto& v : fp.vertices()) {
    far = std::max(far, v.norm());
    near = std::min(near, v.norm());
    EXPECT_GT(v.x(), 0.0);  // in front of the UAV
  }
  EXPECT_LE(far, 150.0 + 1e-9);
  EXPECT_GT(far, 149.0);
  // The lower image border meets the ground at 40 / tan(pitch + vfov / 2).
  const double vhalf = std::atan(240.0 / k.fy);
  EXPECT_NEAR(fp.bounds().min.x(), 40.0 / std::tan(geometry::degToRad(10) + vhalf), 1e-6);
  (void)near;
  EXPECT_EQ(groundFootprint(k, opticalPose(basePose(Vec3(0, 0, 0), 0.0), cam)).size(), 0u);
  EXPECT_EQ(groundFootprint(k, opticalPose(basePose(Vec3(0, 0, 40), 0.0), camera(-60, 60))).size(),
            0u);
}

scenario::Mission aoiMission(geometry::TimeWindow w = {}) {
  scenario::Mission m;
  scenario::AreaOfInterest a;
  a.id = "aoi_1";
  a.polygon = square(0, 0, 20, 20);
  a.window = w;
  m.aois.push_back(a);
  scenario::AreaPrior p;
  p.aoi_id = "aoi_1";
  const double prob[4] = {0.7, 0.1, 0.1, 0.1};
  for (int r = 0; r < 2; ++r) {
    for (int c = 0; c < 2; ++c) {
      scenario::PriorCell cell;
      cell.id = "c" + std::to_string(r) + std::to_string(c);
      cell.row = r;
      cell.col = c;
      cell.polygon = square(c * 10, r * 10, c * 10 + 10, r * 10 + 10);
      cell.probability = prob[r * 2 + c];
      p.cells.push_back(cell);
    }
  }
  m.priors.push_back(p);
  scenario::AreaOfInterest b = a;
  b.id = "aoi_2";
  b.polygon = square(100, 0, 110, 10);
  m.aois.push_back(b);
  return m;
}

TEST(CoverageGrid, CoversCellCentresInTheFootprintWithPriorWeights) {
  CoverageGrid g(aoiMission(), 2.0);
  auto c = g.coverage();
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].cells, 100);
  EXPECT_EQ(c[1].cells, 25);
  EXPECT_TRUE(c[0].has_prior);
  EXPECT_FALSE(c[1].has_prior);
  // The lower-left quadrant (prior 0.7): centres 1, 3, ..., 9 in x and y.
  EXPECT_EQ(g.addFootprint(square(0, 0, 10, 10), 5.0), 25);
  EXPECT_EQ(g.addFootprint(square(0, 0, 10, 10), 6.0), 0);  // already covered
  c = g.coverage();
  EXPECT_EQ(c[0].covered, 25);
  EXPECT_DOUBLE_EQ(c[0].fraction, 0.25);
  EXPECT_NEAR(c[0].prior_weighted, 0.7, 1e-12);
  EXPECT_NEAR(g.priorWeightedCoverage(), 0.7, 1e-12);
  // Part of the upper-right quadrant: centres x = 11..19, y = 11, 13 -> 10 cells; the
  // footprint's left edge runs through the centres x = 11, which count (boundary inside).
  EXPECT_EQ(g.addFootprint(square(11, 10, 20, 14), 7.0), 10);
  c = g.coverage();
  EXPECT_NEAR(c[0].prior_weighted, 0.7 + 0.1 * 10 / 25.0, 1e-12);
  EXPECT_EQ(c[1].covered, 0);
}

TEST(CoverageGrid, OnlyWhileTheWindowIsActive) {
  CoverageGrid g(aoiMission(window(10.0, 20.0)), 2.0);
  EXPECT_EQ(g.addFootprint(square(0, 0, 20, 20), 9.99), 0);
  EXPECT_EQ(g.addFootprint(square(0, 0, 20, 20), 20.01), 0);
  EXPECT_EQ(g.addFootprint(square(0, 0, 20, 20), 10.0), 100);
  EXPECT_NEAR(g.coverage()[0].prior_weighted, 1.0, 1e-12);
  EXPECT_THROW(CoverageGrid(aoiMission(), 0.0), InputError);
}

TEST(CoverageGrid, ShippedMissionFromADownCameraSweep) {
  const auto& m = shippedMission();
  CoverageGrid g(m, 2.0);
  const auto cam = shippedSimConfig().uav.cameras[1];
  ASSERT_EQ(cam.name, "down");
  const auto k = intrinsicsFromHfov(cam.width, cam.height, cam.hfov_deg);
  // Across aoi_2 (open from 130 s) at 50 m: a swath of about 60 m.
  int added = 0;
  for (double x = -300; x <= 10; x += 5) {
    added +=
        g.addFootprint(groundFootprint(k, opticalPose(basePose(Vec3(x, -80, 50), 0), cam)), 150);
  }
  const auto c = g.coverage();
  EXPECT_EQ(c[0].covered, 0);  // aoi_1's window (48..192) is active, but the sweep is elsewhere
  EXPECT_EQ(c[1].covered, added);
  EXPECT_GT(c[1].fraction, 0.15);
  EXPECT_LT(c[1].fraction, 0.5);
  EXPECT_GT(c[1].prior_weighted, 0.0);
}

TEST(IntervalUnion, MergesOverlapsAndTouches) {
  IntervalUnion u;
  u.add(5, 6);
  u.add(1, 2);
  u.add(2, 3);
  u.add(5.5, 7);
  u.add(0, 0.5);
  EXPECT_EQ(u.intervals().size(), 3u);
  EXPECT_DOUBLE_EQ(u.measure(), 0.5 + 2 + 2);
  u.add(0.25, 6);
  EXPECT_EQ(u.intervals().size(), 1u);
  EXPECT_DOUBLE_EQ(u.measure(), 7);
  EXPECT_THROW(u.add(2, 1), InputError);
}

}  // namespace
}  // namespace hameritt::adk
