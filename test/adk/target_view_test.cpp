// Targets without a rendered box: a target hidden in the camera's view is a frame at occlusion
// level "full", one behind the camera, beside the image or beyond the far plane is out of view,
// and a target the renderer boxed keeps the renderer's level. Projections are checked against
// the pinhole formula worked by hand; the scores against the renderer's boxes alone (the frames
// of a hidden target vanish from the levels: the negative control).
#include "hameritt/adk/target_view.h"

#include <gtest/gtest.h>

#include <cmath>

#include "hameritt/scenario/entity.h"

namespace hameritt::adk {
namespace {

// A 640 x 480 camera, 90 degrees wide (fx = fy = 320), looking along +x from (0, 0, 0.75):
// the optical frame's z is world x, its x is -y, its y is -(z - 0.75).
CameraIntrinsics camera() { return intrinsicsFromHfov(640, 480, 90.0); }

Eigen::Isometry3d cameraPose() {
  scenario::CameraSpec spec;
  spec.name = "front";
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() = Eigen::Vector3d(0.0, 0.0, 0.75);
  return opticalPose(base, spec);
}

// A 4.5 x 1.8 x 1.5 m car standing at (x, y) on the ground, facing +x.
geometry::OrientedBox car(double x, double y, double yaw = 0.0) {
  return scenario::boxFromPose(geometry::Vec3(x, y, 0.0), yaw, geometry::Vec3(4.5, 1.8, 1.5));
}

TEST(ProjectBox, InFrontProjectsToThePinholeBounds) {
  // The near face (x = 17.75 m) spans the most pixels: y in [-0.9, 0.9], z - 0.75 in
  // [-0.75, 0.75]; u = 320 X / Z + 319.5 + 0.5, v likewise around 239.5 + 0.5.
  const BoxProjection p = projectBox(camera(), cameraPose(), car(20.0, 0.0));
  ASSERT_TRUE(p.in_view);
  const double du = 320.0 * 0.9 / 17.75, dv = 320.0 * 0.75 / 17.75;
  EXPECT_NEAR(p.box.x, 320.0 - du, 1e-9);
  EXPECT_NEAR(p.box.w, 2.0 * du, 1e-9);
  EXPECT_NEAR(p.box.y, 240.0 - dv, 1e-9);
  EXPECT_NEAR(p.box.h, 2.0 * dv, 1e-9);
  // Turned by 90 degrees the car shows its side: wider than the front view.
  const BoxProjection side = projectBox(camera(), cameraPose(), car(20.0, 0.0, M_PI / 2));
  ASSERT_TRUE(side.in_view);
  EXPECT_NEAR(side.box.w, 2.0 * 320.0 * 2.25 / 19.1, 1e-9);
}

TEST(ProjectBox, BehindBesideOrBeyondIsOutOfView) {
  EXPECT_FALSE(projectBox(camera(), cameraPose(), car(-20.0, 0.0)).in_view);  // behind
  EXPECT_FALSE(projectBox(camera(), cameraPose(), car(20.0, 40.0)).in_view);  // left of the image
  EXPECT_FALSE(projectBox(camera(), cameraPose(), car(20.0, -40.0)).in_view);
  ViewLimits near_far;
  near_far.far_clip = 15.0;
  EXPECT_FALSE(projectBox(camera(), cameraPose(), car(20.0, 0.0), near_far).in_view);
  near_far.far_clip = 18.0;  // the near face at 17.75 m is within it
  EXPECT_TRUE(projectBox(camera(), cameraPose(), car(20.0, 0.0), near_far).in_view);
  // Too small to be drawn: 1.8 m at 400 m is 1.44 px wide.
  EXPECT_FALSE(projectBox(camera(), cameraPose(), car(400.0, 0.0)).in_view);
  ViewLimits tiny;
  tiny.min_side_px = 1.0;
  EXPECT_TRUE(projectBox(camera(), cameraPose(), car(400.0, 0.0), tiny).in_view);
  // Partly out of the image on the left (y from 16.85 to 18.65 m): clipped at u = 0; the right
  // bound is the far face's inner edge, u = 320 (1 - 16.85 / 22.25).
  const BoxProjection edge = projectBox(camera(), cameraPose(), car(20.0, 17.75));
  ASSERT_TRUE(edge.in_view);
  EXPECT_DOUBLE_EQ(edge.box.x, 0.0);
  EXPECT_NEAR(edge.box.w, 320.0 * (1.0 - 16.85 / 22.25), 1e-9);
}

TEST(ProjectBox, BoxAcrossTheNearPlaneFillsTheImage) {
  // The camera stands 1.25 m into the car's length: the part in front spans the whole image.
  const BoxProjection p = projectBox(camera(), cameraPose(), car(1.0, 0.0));
  ASSERT_TRUE(p.in_view);
  EXPECT_DOUBLE_EQ(p.box.x, 0.0);
  EXPECT_DOUBLE_EQ(p.box.y, 0.0);
  EXPECT_DOUBLE_EQ(p.box.w, 640.0);
  EXPECT_DOUBLE_EQ(p.box.h, 480.0);
}

TEST(WithHiddenTargets, HiddenInViewIsFullAndOutOfViewStaysAbsent) {
  const auto k = camera();
  const auto pose = cameraPose();
  // Five frames of car_1: 0 rendered at 30 % occlusion; 1-3 no rendered box, in front of the
  // camera (behind a wall); 4 no rendered box, behind the camera. car_2 is rendered throughout
  // and must stay as the renderer gave it.
  const TargetTruth partial{"car_1", PixelBox{300, 220, 40, 30}, 0.7, 0.3};
  const TargetTruth other{"car_2", PixelBox{10, 10, 30, 20}, 0.5, 0.5};
  std::vector<TrackingFrame> rendered(5), full(5);
  for (int i = 0; i < 5; ++i) {
    rendered[i].t = full[i].t = i;
    rendered[i].targets = {other};
    if (i == 0) rendered[i].targets.push_back(partial);
    const double x = i == 4 ? -20.0 : 20.0;
    full[i].targets = withHiddenTargets(
        rendered[i].targets, {{"car_1", car(x, 0.0)}, {"car_2", car(30.0, 5.0)}}, k, pose);
  }
  ASSERT_EQ(full[0].targets.size(), 2u);
  EXPECT_DOUBLE_EQ(full[0].targets[1].occlusion, 0.3);  // the renderer's level, not replaced
  EXPECT_DOUBLE_EQ(full[0].targets[1].box.x, 300.0);
  EXPECT_DOUBLE_EQ(full[1].targets[0].box.x, 10.0);  // car_2 as rendered, not projected
  ASSERT_EQ(full[1].targets.size(), 2u);
  const TargetTruth& hidden = full[1].targets[1];
  EXPECT_EQ(hidden.id, "car_1");
  EXPECT_DOUBLE_EQ(hidden.occlusion, 1.0);
  EXPECT_DOUBLE_EQ(hidden.visible_fraction, 0.0);
  EXPECT_NEAR(hidden.box.x, 320.0 - 320.0 * 0.9 / 17.75, 1e-9);
  EXPECT_EQ(full[4].targets.size(), 1u);  // behind the camera: out of view
  // The client holds its box on the hidden car in frames 1 and 2 (its centre), loses it in 3.
  full[1].tracks = {{"car_1", hidden.box}};
  full[2].tracks = {{"car_1", PixelBox{hidden.box.x + 5, hidden.box.y, hidden.box.w, 10}}};
  const TargetTrackingScore s = scoreTracking(full, {"car_1"}).targets[0];
  EXPECT_EQ(s.frames, 5u);
  EXPECT_EQ(s.in_view_frames, 4u);
  EXPECT_EQ(s.tracked_frames, 1u);
  const auto& lv = s.by_occlusion[static_cast<std::size_t>(OcclusionLevel::kFull)];
  EXPECT_EQ(lv.frames, 3u);
  EXPECT_DOUBLE_EQ(lv.tracked_fraction, 0.0);
  EXPECT_DOUBLE_EQ(lv.held_fraction, 2.0 / 3.0);
  EXPECT_EQ(s.by_occlusion[static_cast<std::size_t>(OcclusionLevel::kPartial)].frames, 1u);
  EXPECT_EQ(s.scored_frames, 1u);  // UAV123 scores only the frames where the car shows
  // Negative control: the renderer's boxes alone lose the hidden frames from the levels.
  const TargetTrackingScore r = scoreTracking(rendered, {"car_1"}).targets[0];
  EXPECT_EQ(r.in_view_frames, 1u);
  EXPECT_EQ(r.by_occlusion[static_cast<std::size_t>(OcclusionLevel::kFull)].frames, 0u);
  EXPECT_EQ(r.tracked_frames, s.tracked_frames);  // the tracked fraction itself agrees
}

TEST(PoseHistory, InterpolatesAndRefusesStalePoses) {
  PoseHistory h(2.0);
  Eigen::Isometry3d a = Eigen::Isometry3d::Identity(), b = Eigen::Isometry3d::Identity();
  b.translation() = Eigen::Vector3d(10.0, 0.0, 0.0);
  b.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  h.add(1.0, a);
  h.add(2.0, b);
  h.add(1.5, b);  // older than the newest: ignored
  const auto mid = h.at(1.25);
  ASSERT_TRUE(mid.has_value());
  EXPECT_NEAR(mid->translation().x(), 2.5, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(mid->rotation()).angle(), M_PI / 8, 1e-12);
  ASSERT_TRUE(h.at(2.2).has_value());  // the newest, within 0.25 s
  EXPECT_NEAR(h.at(2.2)->translation().x(), 10.0, 1e-12);
  EXPECT_FALSE(h.at(2.3).has_value());
  EXPECT_FALSE(h.at(0.7).has_value());
  // The horizon drops poses older than 2 s before the newest.
  h.add(5.0, a);
  EXPECT_FALSE(h.at(1.0, 0.0).has_value());
  EXPECT_TRUE(h.at(2.0, 0.0).has_value());
}

}  // namespace
}  // namespace hameritt::adk
