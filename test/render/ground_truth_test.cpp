// Depth, labels and boxes of the renderer checked against independent computations: Bullet ray
// casts through pixel centres over the renderer's own scene triangles, the pinhole projection of
// known surface points, recounts of the instance mask, and renders with the occluders hidden.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "hameritt/scenario/trajectory.h"
#include "render_test_util.h"

namespace hameritt::render {
namespace {

using testing::cameraRequest;
using testing::defaultRenderer;
using testing::defaultSimConfig;
using testing::defaultWorld;
using testing::lookAt;
using testing::pixelRay;
using testing::SceneRayCaster;
using testing::uavPose;

constexpr double kTime = 60.0;

const SceneRayCaster& caster() {
  static const SceneRayCaster c(defaultRenderer().sceneTriangles(kTime));
  return c;
}

const scenario::ScenarioEntity& scenarioEntity(const std::string& id) {
  for (const auto& se : defaultSimConfig().entities) {
    if (se.entity.id == id) return se;
  }
  throw std::runtime_error("no scenario entity " + id);
}

RenderRequest clean(RenderRequest r) {
  r.noise = false;
  r.weather = false;
  return r;
}

// The three views of the depth test: the perception path's front camera, a low oblique view
// down the target's street, and the down camera straight over the neighborhood.
std::vector<RenderRequest> depthViews() {
  const auto& cfg = defaultSimConfig();
  const auto p = scenario::sampleTrajectory(cfg.uav.perception_path->trajectory, kTime);
  const Eigen::Isometry3d uav = uavPose(p.x, p.y, p.z, p.yaw);
  std::vector<RenderRequest> views;
  views.push_back(clean(cameraRequest(cfg.uav.cameras[0], uav, kTime)));
  const auto& target = scenarioEntity("car_706").entity;
  RenderRequest low = views.front();
  const Eigen::Vector3d c = target.box.center;
  low.world_T_optical = lookAt(c + Eigen::Vector3d(45.0, 6.0, 7.0), c);
  views.push_back(low);
  views.push_back(clean(cameraRequest(cfg.uav.cameras[1], uav, kTime)));
  EXPECT_NEAR(cfg.uav.cameras[1].mount_rpy.y(), 90.0, 1e-9)
      << "the down camera looks straight down";
  return views;
}

TEST(RenderGroundTruth, DepthAndInstanceEqualRayCastsThroughPixelCentres) {
  Renderer& r = defaultRenderer();
  int samples = 0, hits = 0, misses = 0, depth_bad = 0, instance_bad = 0, sky_bad = 0;
  for (const RenderRequest& req : depthViews()) {
    const FrameSet f = r.render(req);
    // What this view's geometry pass draws: far instances with their coarse meshes.
    const SceneRayCaster view_caster(r.sceneTriangles(req));
    const Intrinsics& k = req.intrinsics;
    const Eigen::Vector3d eye = req.world_T_optical.translation();
    for (int v = 5; v < k.height; v += 16) {
      for (int u = 7; u < k.width; u += 16) {
        ++samples;
        const std::size_t i = static_cast<std::size_t>(v) * k.width + u;
        const Eigen::Vector3d ray = pixelRay(req, u, v);  // optical z = 1
        const auto hit = view_caster.cast(eye, eye + req.far_clip * ray);
        if (!hit.hit) {
          ++misses;
          if (!std::isinf(f.depth[i]) || f.instance[i] != 0 || f.semantic[i] != kSkySemantic)
            ++sky_bad;
          continue;
        }
        ++hits;
        const double expected = hit.fraction * req.far_clip;  // optical z of the hit
        if (!(std::abs(f.depth[i] - expected) <= 0.01 * expected + 0.05)) {
          ++depth_bad;
          if (depth_bad <= 5) {
            std::printf("  depth (%d, %d): rendered %.3f, ray %.3f (instance %d vs %d)\n", u, v,
                        f.depth[i], expected, f.instance[i], hit.instance);
          }
        }
        if (f.instance[i] != hit.instance) ++instance_bad;
      }
    }
  }
  std::printf("%d pixels: %d hits, %d sky; depth off: %d, instance off: %d, sky off: %d\n", samples,
              hits, misses, depth_bad, instance_bad, sky_bad);
  EXPECT_GE(hits, 200);
  EXPECT_GE(misses, 20);  // the oblique views see the sky
  // A pixel centre within float rounding of a silhouette edge can fall on either side in the
  // rasterizer and in Bullet: allow that for at most 2 % of the samples.
  EXPECT_LE(depth_bad, samples / 50);
  EXPECT_LE(instance_bad, samples / 50);
  EXPECT_LE(sky_bad, samples / 50);
}

// Centroids of visible, camera-facing triangles of an instance (well inside the triangle, so
// not on an edge), with the optical z of each.
std::vector<Eigen::Vector3d> visibleSurfacePoints(const SceneRayCaster& caster,
                                                  const RenderRequest& req, int instance,
                                                  std::size_t max) {
  const SceneTriangles& t = caster.triangles();
  const Eigen::Vector3d eye = req.world_T_optical.translation();
  std::vector<Eigen::Vector3d> out;
  for (std::size_t tri = 0; tri < t.triangle_instance.size() && out.size() < max; ++tri) {
    if (t.triangle_instance[tri] != instance) continue;
    const Eigen::Vector3d a = t.vertices[t.indices[3 * tri]].cast<double>();
    const Eigen::Vector3d b = t.vertices[t.indices[3 * tri + 1]].cast<double>();
    const Eigen::Vector3d c = t.vertices[t.indices[3 * tri + 2]].cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 0.05) continue;  // small: at most a few pixels
    const Eigen::Vector3d centroid = (a + b + c) / 3.0;
    if (n.dot(eye - centroid) <= 0) continue;
    const auto hit = caster.cast(eye, eye + 1.02 * (centroid - eye));
    if (!hit.hit || hit.triangle != static_cast<int>(tri)) continue;  // something in front
    out.push_back(centroid);
  }
  return out;
}

TEST(RenderGroundTruth, ProjectedSurfacePointsLandOnTheirPixels) {
  Renderer& r = defaultRenderer();
  const auto& target = scenarioEntity("car_706").entity;
  const Eigen::Vector3d c = target.box.center;
  RenderRequest req = clean(RenderRequest{});
  req.intrinsics = intrinsicsFromHfov(640, 480, 70.0);
  req.time = kTime;
  req.world_T_optical = lookAt(c + Eigen::Vector3d(-14.0, -16.0, 12.0), c);
  const FrameSet f = r.render(req);
  const SceneRayCaster view_caster(r.sceneTriangles(req));  // this view's levels of detail
  // The target car and the houses in view.
  std::set<int> instances = {r.instanceOf("car_706")};
  for (std::uint16_t id : f.instance) {
    if (id != 0 && r.instanceEntityId(id).rfind("house_", 0) == 0) instances.insert(id);
  }
  ASSERT_GE(instances.size(), 2u) << "a house in view";
  int points = 0, landed = 0;
  for (int id : instances) {
    for (const Eigen::Vector3d& p : visibleSurfacePoints(view_caster, req, id, 40)) {
      Eigen::Vector2d uv;
      ASSERT_TRUE(projectPoint(req.intrinsics, req.world_T_optical, p, &uv));
      const int u = static_cast<int>(std::lround(uv.x())),
                v = static_cast<int>(std::lround(uv.y()));
      if (u < 1 || v < 1 || u >= req.intrinsics.width - 1 || v >= req.intrinsics.height - 1)
        continue;
      ++points;
      const double z = (req.world_T_optical.inverse() * p).z();
      bool found = false;
      for (int dv = -1; dv <= 1 && !found; ++dv) {
        for (int du = -1; du <= 1 && !found; ++du) {
          const std::size_t i = static_cast<std::size_t>(v + dv) * req.intrinsics.width + (u + du);
          found = f.instance[i] == id && std::abs(f.depth[i] - z) <= 0.01 * z + 0.05;
        }
      }
      if (found) ++landed;
    }
  }
  EXPECT_GE(points, 20);
  EXPECT_EQ(landed, points) << "every visible surface point is drawn within 1 px of its projection";
}

TEST(RenderGroundTruth, BoxesContainExactlyTheirInstancesPixels) {
  Renderer& r = defaultRenderer();
  const auto& cfg = defaultSimConfig();
  const auto p = scenario::sampleTrajectory(cfg.uav.perception_path->trajectory, kTime);
  const FrameSet f =
      r.render(cameraRequest(cfg.uav.cameras[0], uavPose(p.x, p.y, p.z, p.yaw), kTime));
  ASSERT_GE(f.boxes.size(), 5u);
  struct Count {
    int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1, n = 0;
  };
  std::map<int, Count> counts;
  const int w = f.intrinsics.width;
  for (std::size_t i = 0; i < f.instance.size(); ++i) {
    const int id = f.instance[i];
    const int sem = f.semantic[i];
    if (sem != scenario::semanticId(scenario::EntityClass::kCar) &&
        sem != scenario::semanticId(scenario::EntityClass::kPedestrian)) {
      continue;
    }
    Count& c = counts[id];
    const int x = static_cast<int>(i) % w, y = static_cast<int>(i) / w;
    c.x0 = std::min(c.x0, x);
    c.x1 = std::max(c.x1, x);
    c.y0 = std::min(c.y0, y);
    c.y1 = std::max(c.y1, y);
    ++c.n;
  }
  ASSERT_EQ(f.boxes.size(), counts.size()) << "one box per car or pedestrian in the mask";
  int prev = 0;
  for (const BoundingBox& b : f.boxes) {
    EXPECT_GT(b.instance, prev) << "sorted by instance";
    prev = b.instance;
    ASSERT_TRUE(counts.count(b.instance));
    const Count& c = counts[b.instance];
    EXPECT_EQ(b.x_min, c.x0);
    EXPECT_EQ(b.y_min, c.y0);
    EXPECT_EQ(b.x_max, c.x1);
    EXPECT_EQ(b.y_max, c.y1);
    EXPECT_EQ(b.visible_pixels, c.n);
    EXPECT_GE(b.total_pixels, b.visible_pixels);
    EXPECT_NEAR(b.occlusion, 1.0 - static_cast<double>(b.visible_pixels) / b.total_pixels, 1e-12);
    EXPECT_EQ(b.entity_id, r.instanceEntityId(b.instance));
    const bool world = b.instance <= static_cast<int>(defaultWorld().entities().size());
    if (world) {
      EXPECT_EQ(b.role, "world");
    } else {
      EXPECT_EQ(b.role, scenarioEntity(b.entity_id).role);
    }
  }
}

// Pixels of `id` in a render with every other entity hidden (nothing left that can be in front
// of it: the ground layers lie below every object).
int aloneCount(const RenderRequest& base, int id) {
  Renderer& r = defaultRenderer();
  RenderRequest req = base;
  req.hidden_entities.clear();
  for (int i = 1; i < r.instanceCount(); ++i) {
    const std::string& e = r.instanceEntityId(i);
    if (i != id && !e.empty() && e != "uav") req.hidden_entities.push_back(e);
  }
  const FrameSet f = r.render(req);
  return static_cast<int>(std::count(f.instance.begin(), f.instance.end(), id));
}

const BoundingBox* boxOf(const FrameSet& f, int id) {
  for (const auto& b : f.boxes) {
    if (b.instance == id) return &b;
  }
  return nullptr;
}

TEST(RenderGroundTruth, UnoccludedCarIsFullyVisibleAndTotalEqualsItsCoverage) {
  Renderer& r = defaultRenderer();
  const auto& target = scenarioEntity("car_706").entity;
  RenderRequest req = clean(RenderRequest{});
  req.intrinsics = intrinsicsFromHfov(320, 240, 60.0);
  req.time = kTime;
  req.world_T_optical =
      lookAt(target.box.center + Eigen::Vector3d(0.5, 0.3, 25.0), target.box.center);
  const int id = r.instanceOf("car_706");
  const FrameSet f = r.render(req);
  const BoundingBox* b = boxOf(f, id);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(b->role, "target");
  EXPECT_GT(b->visible_pixels, 200);
  EXPECT_EQ(b->total_pixels, aloneCount(req, id));
  EXPECT_EQ(b->visible_pixels, b->total_pixels);
  EXPECT_EQ(b->occlusion, 0.0);
}

// A parked world car, a house beside it, and a low camera on the far side of the house looking
// at the car: the house hides it fully. Moved sideways, the house hides part of it.
TEST(RenderGroundTruth, HouseBetweenCameraAndCarHidesItFullyOrPartly) {
  Renderer& r = defaultRenderer();
  const auto& ents = defaultWorld().entities();
  RenderRequest base = clean(RenderRequest{});
  base.intrinsics = intrinsicsFromHfov(200, 150, 45.0);
  base.time = kTime;
  bool full_done = false, partial_done = false;
  int tried = 0, renders = 0;
  for (std::size_t ci = 0; ci < ents.size() && !(full_done && partial_done) && tried < 60; ++ci) {
    const auto& car = ents[ci];
    if (car.cls != scenario::EntityClass::kCar) continue;
    for (std::size_t hi = 0; hi < ents.size() && !(full_done && partial_done); ++hi) {
      const auto& house = ents[hi];
      if (house.cls != scenario::EntityClass::kHouse) continue;
      const double d = (house.box.center2() - car.box.center2()).norm();
      if (d < 8.0 || d > 20.0) continue;
      ++tried;
      const Eigen::Vector2d dir = (house.box.center2() - car.box.center2()).normalized();
      const Eigen::Vector2d side(-dir.y(), dir.x());
      const Eigen::Vector3d aim = car.box.center;
      const int id = static_cast<int>(ci) + 1;
      ASSERT_EQ(r.instanceOf(car.id), id);
      // Straight behind the house, and with the line of sight to the car's centre grazing
      // either side edge of the house (half the car hidden).
      const double back = 14.0;
      double s_min = 0, s_max = 0;
      for (const auto& corner : house.box.corners2()) {
        const double s = (corner - car.box.center2()).dot(side);
        s_min = std::min(s_min, s);
        s_max = std::max(s_max, s);
      }
      const double scale = (d + back) / d;
      for (double lateral : {0.0, s_max * scale, s_min * scale}) {
        if (full_done && partial_done) break;
        ++renders;
        const Eigen::Vector2d e2 = house.box.center2() + 14.0 * dir + lateral * side;
        RenderRequest req = base;
        req.world_T_optical = lookAt(Eigen::Vector3d(e2.x(), e2.y(), 1.6), aim);
        RenderRequest no_house = req;
        no_house.hidden_entities = {house.id};
        const FrameSet open = r.render(no_house);
        const BoundingBox* seen = boxOf(open, id);
        if (seen == nullptr || seen->visible_pixels < 40) continue;  // hidden by more, or tiny
        const FrameSet f = r.render(req);
        const BoundingBox* b = boxOf(f, id);
        const int visible = static_cast<int>(std::count(f.instance.begin(), f.instance.end(), id));
        if (visible != 0 && (b == nullptr || visible > b->total_pixels - 10 || partial_done))
          continue;
        const int alone = aloneCount(req, id);
        if (!full_done && visible == 0) {
          EXPECT_EQ(b, nullptr) << car.id << " behind " << house.id << " has no box";
          EXPECT_EQ(seen->total_pixels, alone);
          full_done = true;
        } else if (!partial_done && b != nullptr && visible > 10 && visible < alone - 10) {
          EXPECT_EQ(b->visible_pixels, visible);
          EXPECT_EQ(b->total_pixels, alone) << car.id << " partly behind " << house.id;
          EXPECT_NEAR(b->occlusion, 1.0 - static_cast<double>(visible) / alone, 1e-12);
          EXPECT_GT(b->occlusion, 0.0);
          EXPECT_LT(b->occlusion, 1.0);
          partial_done = true;
        }
      }
    }
  }
  std::printf("%d car-house pairs, %d views tried\n", tried, renders);
  EXPECT_TRUE(full_done) << "no fully hidden configuration found in " << tried
                         << " car-house pairs";
  EXPECT_TRUE(partial_done) << "no partly hidden configuration found in " << tried << " pairs";
}

TEST(RenderGroundTruth, MoversAreDrawnAtTheirTrajectoryPoseAtTheRequestTime) {
  Renderer& r = defaultRenderer();
  const auto& se = scenarioEntity("car_708");  // traffic, driving
  ASSERT_FALSE(se.trajectory.empty());
  RenderRequest req = clean(RenderRequest{});
  req.intrinsics = intrinsicsFromHfov(320, 240, 60.0);
  const int id = r.instanceOf("car_708");
  Eigen::Vector2d first;
  for (double t : {5.0, 25.0}) {
    const auto p = scenario::sampleTrajectory(se.trajectory, t);
    const Eigen::Vector3d c(p.x, p.y, p.z + 0.5 * se.entity.box.size.z());
    req.time = t;
    req.world_T_optical = lookAt(c + Eigen::Vector3d(0.3, 0.2, 30.0), c);
    const FrameSet f = r.render(req);
    Eigen::Vector2d uv;
    ASSERT_TRUE(projectPoint(req.intrinsics, req.world_T_optical, c, &uv));
    const std::size_t i = static_cast<std::size_t>(std::lround(uv.y())) * 320 + std::lround(uv.x());
    EXPECT_EQ(f.instance[i], id) << "t = " << t;
    if (t == 5.0)
      first = Eigen::Vector2d(p.x, p.y);
    else
      EXPECT_GT((Eigen::Vector2d(p.x, p.y) - first).norm(), 20.0) << "it moved";
  }
}

TEST(RenderGroundTruth, SameRequestGivesTheSameFrameByteForByte) {
  Renderer& r = defaultRenderer();
  const auto& cfg = defaultSimConfig();
  const auto p = scenario::sampleTrajectory(cfg.uav.perception_path->trajectory, kTime);
  RenderRequest req = cameraRequest(cfg.uav.cameras[0], uavPose(p.x, p.y, p.z, p.yaw), kTime);
  req.frame_index = 17;
  const FrameSet a = r.render(req);
  FrameSet b;
  r.render(cameraRequest(cfg.uav.cameras[1], uavPose(p.x, p.y, p.z, p.yaw), kTime), &b);  // reuse
  r.render(req, &b);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(std::memcmp(a.depth.data(), b.depth.data(), a.depth.size() * sizeof(float)), 0);
  EXPECT_EQ(a.semantic, b.semantic);
  EXPECT_EQ(a.instance, b.instance);
  ASSERT_EQ(a.boxes.size(), b.boxes.size());
  for (std::size_t i = 0; i < a.boxes.size(); ++i) {
    EXPECT_EQ(a.boxes[i].instance, b.boxes[i].instance);
    EXPECT_EQ(a.boxes[i].total_pixels, b.boxes[i].total_pixels);
  }
}

TEST(RenderGroundTruth, BatchOfRequestsEqualsOneRenderEach) {
  Renderer& r = defaultRenderer();
  const auto& cfg = defaultSimConfig();
  std::vector<RenderRequest> reqs;
  for (double t : {30.0, 60.0}) {
    const auto p = scenario::sampleTrajectory(cfg.uav.perception_path->trajectory, t);
    for (int c = 0; c < 2; ++c) {
      RenderRequest q = cameraRequest(cfg.uav.cameras[static_cast<std::size_t>(c)],
                                      uavPose(p.x, p.y, p.z, p.yaw), t);
      q.camera_index = c;
      q.frame_index = static_cast<std::uint64_t>(t);
      reqs.push_back(q);
    }
  }
  reqs[1].hidden_entities = {"car_706"};
  reqs[2].intrinsics = intrinsicsFromHfov(200, 100, 80);  // another size in the same batch
  std::vector<FrameSet> batch;
  r.render(reqs, &batch);
  ASSERT_EQ(batch.size(), reqs.size());
  for (std::size_t i = 0; i < reqs.size(); ++i) {
    const FrameSet one = r.render(reqs[i]);
    EXPECT_EQ(batch[i].rgb, one.rgb) << i;
    EXPECT_EQ(
        std::memcmp(batch[i].depth.data(), one.depth.data(), one.depth.size() * sizeof(float)), 0)
        << i;
    EXPECT_EQ(batch[i].instance, one.instance) << i;
    ASSERT_EQ(batch[i].boxes.size(), one.boxes.size()) << i;
    for (std::size_t k = 0; k < one.boxes.size(); ++k) {
      EXPECT_EQ(batch[i].boxes[k].instance, one.boxes[k].instance);
      EXPECT_EQ(batch[i].boxes[k].visible_pixels, one.boxes[k].visible_pixels);
      EXPECT_EQ(batch[i].boxes[k].total_pixels, one.boxes[k].total_pixels);
    }
    EXPECT_EQ(batch[i].time, reqs[i].time);
  }
  EXPECT_EQ(std::count(batch[1].instance.begin(), batch[1].instance.end(), r.instanceOf("car_706")),
            0);
}

TEST(RenderGroundTruth, UavModelIsDrawnOnlyWhenAsked) {
  Renderer& r = defaultRenderer();
  RenderRequest req = clean(RenderRequest{});
  req.intrinsics = intrinsicsFromHfov(160, 120, 60.0);
  const Eigen::Isometry3d uav = uavPose(-271.0, 249.0, 30.0, 0.4);
  req.world_T_uav = uav;
  req.world_T_optical = lookAt(uav.translation() + Eigen::Vector3d(1.2, -0.9, 0.6), uav.translation());
  const FrameSet without = r.render(req);
  req.draw_uav = true;
  const FrameSet with = r.render(req);
  const int id = r.instanceCount() - 1;
  EXPECT_EQ(r.instanceEntityId(id), "uav");
  EXPECT_EQ(std::count(without.semantic.begin(), without.semantic.end(), kUavSemantic), 0);
  const auto n = std::count(with.semantic.begin(), with.semantic.end(), kUavSemantic);
  EXPECT_GT(n, 100) << "the UAV fills part of a close view";
  EXPECT_EQ(std::count(with.instance.begin(), with.instance.end(), id), n);
  Eigen::Vector2d uv;
  ASSERT_TRUE(projectPoint(req.intrinsics, req.world_T_optical, uav.translation(), &uv));
  const std::size_t centre = static_cast<std::size_t>(std::lround(uv.y())) * 160 + std::lround(uv.x());
  EXPECT_EQ(with.instance[centre], id);
  EXPECT_LT(with.depth[centre], 1.6f);
}

// An avoid scenario's other aircraft: an airplane crossing the neighbourhood at 40 m and a
// quadrotor climbing across it, drawn at their trajectory pose with their own meshes, labelled
// with class aircraft and boxed with role "aircraft".
TEST(RenderGroundTruth, AircraftAreDrawnLabelledAndBoxedAtTheirTrajectoryPose) {
  scenario::SimConfig cfg = defaultSimConfig();
  const geometry::Aabb2 bounds = defaultWorld().bounds();
  const geometry::Vec2 mid = 0.5 * (bounds.min + bounds.max);
  scenario::Aircraft plane;
  plane.id = "aircraft_1";
  plane.model = "fixed_wing";
  plane.size = geometry::Vec3(1.8, 2.4, 0.45);
  plane.trajectory = {{0.0, mid.x() - 150.0, mid.y(), 40.0, 0.0},
                      {60.0, mid.x() + 450.0, mid.y(), 40.0, 0.0}};
  scenario::Aircraft quad;
  quad.id = "aircraft_2";
  quad.model = "quadrotor";
  quad.size = geometry::Vec3(0.7, 0.7, 0.25);
  quad.trajectory = {{0.0, mid.x(), mid.y() - 60.0, 20.0, 1.57},
                     {60.0, mid.x(), mid.y() + 240.0, 50.0, 1.57}};
  cfg.aircraft = {plane, quad};
  Renderer r(defaultWorld(), cfg);
  const int n_before = defaultRenderer().instanceCount();
  EXPECT_EQ(r.instanceCount(), n_before + 2) << "two more instances, the UAV's id moves up";
  EXPECT_EQ(r.instanceEntityId(r.instanceCount() - 1), "uav");
  for (const auto& a : cfg.aircraft) {
    const int id = r.instanceOf(a.id);
    ASSERT_GT(id, 0) << a.id;
    const double range = a.model == "fixed_wing" ? 9.0 : 3.0;
    for (double t : {5.0, 25.0}) {
      const auto p = scenario::sampleTrajectory(a.trajectory, t);
      const Eigen::Vector3d c(p.x, p.y, p.z);  // the body centre
      RenderRequest req = clean(RenderRequest{});
      req.intrinsics = intrinsicsFromHfov(160, 120, 60.0);
      req.time = t;
      req.world_T_optical = lookAt(c + Eigen::Vector3d(0.2, 0.1, range), c);
      const FrameSet f = r.render(req);
      Eigen::Vector2d uv;
      ASSERT_TRUE(projectPoint(req.intrinsics, req.world_T_optical, c, &uv));
      const std::size_t i =
          static_cast<std::size_t>(std::lround(uv.y())) * 160 + std::lround(uv.x());
      EXPECT_EQ(f.instance[i], id) << a.id << " at t = " << t;
      EXPECT_EQ(f.semantic[i], scenario::semanticId(scenario::EntityClass::kAircraft));
      EXPECT_LT(f.depth[i], range) << "its top is nearer than its centre";
      const BoundingBox* b = boxOf(f, id);
      ASSERT_NE(b, nullptr) << a.id << " at t = " << t;
      EXPECT_EQ(b->entity_id, a.id);
      EXPECT_EQ(b->role, "aircraft");
      EXPECT_EQ(b->cls, scenario::EntityClass::kAircraft);
      EXPECT_GT(b->visible_pixels, 200) << "a close view";
      EXPECT_EQ(b->occlusion, 0.0);
      // Negative control: 20 s later the aircraft has flown on and the same view is empty of it.
      req.time = t + 20.0;
      const FrameSet later = r.render(req);
      EXPECT_EQ(std::count(later.instance.begin(), later.instance.end(), id), 0)
          << a.id << " is not drawn where it was";
      EXPECT_EQ(boxOf(later, id), nullptr);
    }
  }
  // An unknown model is refused, naming the attribute.
  cfg.aircraft[1].model = "balloon";
  try {
    Renderer bad(defaultWorld(), cfg);
    ADD_FAILURE() << "an unknown aircraft model was accepted";
  } catch (const RenderError& e) {
    EXPECT_NE(std::string(e.what()).find("model"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fixed_wing or quadrotor"), std::string::npos) << e.what();
  }
}

TEST(RenderGroundTruth, SceneTrianglesCarryValidInstances) {
  Renderer& r = defaultRenderer();
  const SceneTriangles& t = caster().triangles();
  ASSERT_EQ(t.indices.size(), 3 * t.triangle_instance.size());
  std::set<int> seen;
  for (int id : t.triangle_instance) {
    ASSERT_GE(id, 0);
    ASSERT_LT(id, r.instanceCount());
    seen.insert(id);
  }
  // Ground (0) and every world and scenario entity; the UAV model is not part of the scene.
  EXPECT_EQ(static_cast<int>(seen.size()), r.instanceCount() - 1);
  EXPECT_EQ(r.instanceEntityId(r.instanceCount() - 1), "uav");
  EXPECT_EQ(r.instanceEntityId(0), "");
  EXPECT_EQ(r.instanceEntityId(r.instanceCount()), "");
  EXPECT_EQ(r.instanceOf("car_706"), static_cast<int>(defaultWorld().entities().size()) + 1);
}

}  // namespace
}  // namespace hameritt::render
