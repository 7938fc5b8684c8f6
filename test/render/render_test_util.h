#pragma once
// Shared fixtures of the renderer tests: the shipped default scenario, its world and one
// renderer for it (built once per test binary), camera poses, and a Bullet ray caster over the
// renderer's own scene triangles.

#include "hameritt/build_paths.h"
#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <btBulletCollisionCommon.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "hameritt/render/renderer.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/world.h"

namespace hameritt::render::testing {

inline std::string defaultSimConfigPath() {
  return std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/sim_config.json";
}

inline const scenario::SimConfig& defaultSimConfig() {
  static const scenario::SimConfig c = scenario::loadSimConfig(defaultSimConfigPath());
  return c;
}

inline const scenario::World& defaultWorld() {
  static const scenario::World w =
      scenario::generateCheckedWorld(defaultSimConfig(), defaultSimConfigPath());
  return w;
}

// The default scenario as shipped (time of day, rain, noise and all).
inline Renderer& defaultRenderer() {
  static Renderer r(defaultWorld(), defaultSimConfig());
  return r;
}

// The UAV level at (x, y, z) with heading yaw.
inline Eigen::Isometry3d uavPose(double x, double y, double z, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(x, y, z);
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

// A camera at `eye` looking at `target` with the image rows level (optical x right, y down).
inline Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear().col(0) = x;
  t.linear().col(1) = y;
  t.linear().col(2) = z;
  t.translation() = eye;
  return t;
}

// A request of a payload camera of the default scenario on the UAV at world_T_base.
inline RenderRequest cameraRequest(const scenario::CameraSpec& cam,
                                   const Eigen::Isometry3d& world_T_base, double time) {
  RenderRequest r;
  r.intrinsics = intrinsicsFromHfov(cam.width, cam.height, cam.hfov_deg);
  r.world_T_optical = opticalPose(world_T_base, cam.mount_xyz, cam.mount_rpy * (M_PI / 180.0));
  r.time = time;
  return r;
}

// The scene triangles in a Bullet BVH; rays report the nearest front face and its instance.
class SceneRayCaster {
 public:
  explicit SceneRayCaster(SceneTriangles t) : tri_(std::move(t)) {
    btIndexedMesh mesh;
    mesh.m_numTriangles = static_cast<int>(tri_.indices.size() / 3);
    mesh.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(tri_.indices.data());
    mesh.m_triangleIndexStride = 3 * sizeof(std::uint32_t);
    mesh.m_numVertices = static_cast<int>(tri_.vertices.size());
    mesh.m_vertexBase = reinterpret_cast<const unsigned char*>(tri_.vertices.data());
    mesh.m_vertexStride = sizeof(Eigen::Vector3f);
    mesh.m_indexType = PHY_INTEGER;
    mesh.m_vertexType = PHY_FLOAT;
    array_ = std::make_unique<btTriangleIndexVertexArray>();
    array_->addIndexedMesh(mesh, PHY_INTEGER);
    shape_ = std::make_unique<btBvhTriangleMeshShape>(array_.get(), true);
  }

  struct Hit {
    bool hit = false;
    double fraction = 1.0;
    int triangle = -1;
    int instance = 0;
  };

  // Nearest front-facing triangle on the segment [from, to] (back faces are culled, as in the
  // renderer).
  Hit cast(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const {
    struct Callback : btTriangleRaycastCallback {
      Callback(const btVector3& f, const btVector3& t)
          : btTriangleRaycastCallback(f, t, kF_FilterBackfaces) {}
      btScalar reportHit(const btVector3&, btScalar fraction, int, int triangle) override {
        if (fraction < best) {
          best = fraction;
          index = triangle;
        }
        return fraction;
      }
      btScalar best = 1.0;
      int index = -1;
    };
    const btVector3 f(btScalar(from.x()), btScalar(from.y()), btScalar(from.z()));
    const btVector3 t(btScalar(to.x()), btScalar(to.y()), btScalar(to.z()));
    Callback cb(f, t);
    shape_->performRaycast(&cb, f, t);
    Hit h;
    if (cb.index >= 0) {
      h.hit = true;
      h.fraction = cb.best;
      h.triangle = cb.index;
      h.instance = tri_.triangle_instance[static_cast<std::size_t>(cb.index)];
    }
    return h;
  }

  const SceneTriangles& triangles() const { return tri_; }

 private:
  SceneTriangles tri_;
  std::unique_ptr<btTriangleIndexVertexArray> array_;
  std::unique_ptr<btBvhTriangleMeshShape> shape_;
};

// World point and direction of the ray through pixel centre (u, v), scaled so that its optical
// z component is 1.
inline Eigen::Vector3d pixelRay(const RenderRequest& r, double u, double v) {
  const Intrinsics& k = r.intrinsics;
  return r.world_T_optical.linear() * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
}

}  // namespace hameritt::render::testing
