// The colour/shape detector on real down-camera frames of a track mission: the track scenario
// of test_mission_track.py (`hameritt_generate --class track --count 1 --seed 8`: a green Toyota
// RAV4 driving through the suburb, in light snow) rendered from straight above the car, where
// the baseline's track viewpoint puts the UAV (20 m above the predicted car), along its drive.
// The detector that knows the (public) weather must find the target there (a blob within 3 m of
// it) in most frames, as the track client's reports from the detector need, and accept no blob
// where no car of the target's colour is. From 8 m behind (a pursuit lags the car) the image
// border cuts the car: no longer measurable, but still a trackable blob (the box a track needs). Ground truth (the cars' trajectories) places the
// camera and judges; the detector sees only the image and the depth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "hameritt/clients/color_detector.h"
#include "hameritt/clients/context_filter.h"
#include "hameritt/generation/generator.h"
#include "hameritt/render/renderer.h"
#include "hameritt/scenario/generator_config.h"
#include "hameritt/scenario/trajectory.h"

namespace hameritt::clients {
namespace {

using geometry::Vec3;

TEST(TrackDetector, DownCameraFindsTheDrivingTargetInSnowFromAbove) {
  const scenario::World world = scenario::generateWorld(
      scenario::loadWorldParams(scenario::defaultConfigDir() + "/world.json"));
  const scenario::GeneratorConfig gc =
      scenario::loadGeneratorConfig(scenario::defaultConfigDir() + "/generator.json");
  const scenario::Scenario s = scenario::generateScenario(
      world, gc, scenario::ScenarioClass::kTrack, scenario::batchSeed(8, 0));
  const scenario::TargetDescription& target = s.mission.objective.targets.front();
  const scenario::ScenarioEntity* car = nullptr;
  for (const auto& se : s.sim.entities) {
    if (se.entity.id == target.id) car = &se;
  }
  ASSERT_NE(car, nullptr);
  ASSERT_FALSE(car->trajectory.empty());
  ASSERT_GT(s.sim.environment.snow, 0.1);  // the snow whitens the roof the down camera sees
  const scenario::CameraSpec* down = nullptr;
  int camera_index = -1;
  for (std::size_t i = 0; i < s.sim.uav.cameras.size(); ++i) {
    if (s.sim.uav.cameras[i].name == "down") {
      down = &s.sim.uav.cameras[i];
      camera_index = static_cast<int>(i);
    }
  }
  ASSERT_NE(down, nullptr);
  // Where the nearest car of the target's colour is at time t, other than the target.
  auto nearestLookAlike = [&](const Vec3& at, double t) {
    double nearest = 1e9;
    auto consider = [&](const scenario::Entity& e, const Vec3& p) {
      if (e.id == target.id || e.cls != scenario::EntityClass::kCar ||
          e.attributes.str("color") != target.color) {
        return;
      }
      nearest = std::min(nearest, std::hypot(p.x() - at.x(), p.y() - at.y()));
    };
    for (const auto& e : world.entities()) consider(e, e.position());
    for (const auto& se : s.sim.entities) {
      if (se.trajectory.empty()) {
        consider(se.entity, se.entity.position());
      } else {
        const scenario::TrajectoryPoint q = scenario::sampleTrajectory(se.trajectory, t);
        consider(se.entity, Vec3(q.x, q.y, q.z));
      }
    }
    return nearest;
  };
  render::Renderer renderer(world, s.sim);
  DetectorSettings aware = defaultDetectorSettings();
  aware.snow = s.sim.environment.snow;  // the public weather, as the detector node sets it
  const ColorShapeDetector with_weather(aware), blind(defaultDetectorSettings());
  struct Count {
    int frames = 0, found = 0, found_blind = 0, trackable = 0, false_blobs = 0, look_alikes = 0;
  };
  // Frames from 20 m above the car, `back` m behind it along its heading (a pursuit lags).
  auto flyOver = [&](double back) {
    Count n;
    for (double t = 30.0; t <= 120.0; t += 5.0) {
      const scenario::TrajectoryPoint p = scenario::sampleTrajectory(car->trajectory, t);
      Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
      base.translation() = Eigen::Vector3d(p.x - back * std::cos(p.yaw),
                                           p.y - back * std::sin(p.yaw), p.z + 20.0);
      base.linear() = Eigen::AngleAxisd(p.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      render::RenderRequest req;
      req.intrinsics = render::intrinsicsFromHfov(down->width, down->height, down->hfov_deg);
      req.world_T_optical =
          render::opticalPose(base, down->mount_xyz, down->mount_rpy * (M_PI / 180.0));
      req.time = t;
      req.camera_index = camera_index;
      const render::FrameSet f = renderer.render(req);
      const cv::Mat rgb(f.intrinsics.height, f.intrinsics.width, CV_8UC3,
                        const_cast<std::uint8_t*>(f.rgb.data()));
      const cv::Mat depth(f.intrinsics.height, f.intrinsics.width, CV_32FC1,
                          const_cast<float*>(f.depth.data()));
      const PinholeCamera cam = pinholeFromHfov(down->width, down->height, down->hfov_deg);
      const Eigen::Isometry3d pose = opticalPose(base, down->mount_xyz, down->mount_rpy);
      ++n.frames;
      const Vec3 size = nominalSize(target);
      bool hit = false, kept = false;
      for (const auto& c : with_weather.detect(rgb, depth, cam, pose, target.color, size)) {
        const double from_target = std::hypot(c.position.x() - p.x, c.position.y() - p.y);
        kept |= with_weather.trackable(c, size) && from_target <= 3.0;
        if (!c.reject.empty()) continue;
        if (from_target <= 3.0) {
          hit = true;
        } else {
          // Another car of the target's colour is a right detection, not a false one.
          (nearestLookAlike(c.position, t) <= 3.0 ? n.look_alikes : n.false_blobs) += 1;
        }
      }
      n.found += hit;
      n.trackable += kept;
      for (const auto& c : blind.detect(rgb, depth, cam, pose, target.color, size)) {
        if (c.reject.empty() && std::hypot(c.position.x() - p.x, c.position.y() - p.y) <= 3.0) {
          ++n.found_blind;
          break;
        }
      }
    }
    return n;
  };
  const Count above = flyOver(0.0), lagging = flyOver(8.0);
  std::printf(
      "snow %.2f, from above: the target found in %d of %d down-camera frames (%d without the "
      "weather); look-alikes found %d, blobs where no %s car is %d\n",
      s.sim.environment.snow, above.found, above.frames, above.found_blind, above.look_alikes,
      target.color.c_str(), above.false_blobs);
  std::printf("8 m behind: found (measured) in %d of %d frames, a trackable blob in %d\n",
              lagging.found, lagging.frames, lagging.trackable);
  EXPECT_GE(above.found * 10, above.frames * 8);
  EXPECT_EQ(above.false_blobs + lagging.false_blobs, 0);
  EXPECT_GT(above.look_alikes, 0);  // the scenario's green look-alikes pass under the camera
  // The control: blind to the snow, the whitened roof is not green enough.
  EXPECT_LE(above.found_blind * 10, above.frames * 2);
  // 8 m behind, the image border cuts the car: not measurable, but its box is the track's.
  EXPECT_GE(lagging.trackable * 10, lagging.frames * 8);
  EXPECT_LE(lagging.found * 10, lagging.frames * 2);
}

}  // namespace
}  // namespace hameritt::clients
