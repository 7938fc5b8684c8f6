// Intrinsics and camera poses (renderer.h).

#include <cmath>
#include <string>

#include "hameritt/render/renderer.h"
#include "hameritt/scenario/error.h"

namespace hameritt::render {

Intrinsics intrinsicsFromHfov(int width, int height, double hfov_deg) {
  if (width < 1 || height < 1) {
    throw RenderError("intrinsics: width and height must be >= 1, got " + std::to_string(width) +
                      " x " + std::to_string(height));
  }
  if (!std::isfinite(hfov_deg) || hfov_deg <= 0.0 || hfov_deg >= 180.0) {
    throw RenderError("intrinsics: hfov_deg must be in (0, 180), got " +
                      scenario::formatNumber(hfov_deg));
  }
  Intrinsics k;
  k.width = width;
  k.height = height;
  k.fx = k.fy = 0.5 * width / std::tan(0.5 * hfov_deg * 3.14159265358979323846 / 180.0);
  k.cx = 0.5 * (width - 1);
  k.cy = 0.5 * (height - 1);
  return k;
}

Eigen::Isometry3d opticalPose(const Eigen::Isometry3d& world_T_base,
                              const Eigen::Vector3d& mount_xyz, const Eigen::Vector3d& mount_rpy) {
  // base_T_link: the camera link in FLU (x forward) with fixed-axis roll-pitch-yaw (URDF).
  Eigen::Isometry3d base_T_link = Eigen::Isometry3d::Identity();
  base_T_link.translation() = mount_xyz;
  base_T_link.linear() = (Eigen::AngleAxisd(mount_rpy.z(), Eigen::Vector3d::UnitZ()) *
                          Eigen::AngleAxisd(mount_rpy.y(), Eigen::Vector3d::UnitY()) *
                          Eigen::AngleAxisd(mount_rpy.x(), Eigen::Vector3d::UnitX()))
                             .toRotationMatrix();
  // link_T_optical (REP 103): optical z = link x, optical x = -link y, optical y = -link z.
  Eigen::Matrix3d r;
  r << 0, 0, 1,  //
      -1, 0, 0,  //
      0, -1, 0;
  Eigen::Isometry3d link_T_optical = Eigen::Isometry3d::Identity();
  link_T_optical.linear() = r;
  return world_T_base * base_T_link * link_T_optical;
}

bool projectPoint(const Intrinsics& k, const Eigen::Isometry3d& world_T_optical,
                  const Eigen::Vector3d& p_world, Eigen::Vector2d* uv) {
  const Eigen::Vector3d q = world_T_optical.inverse() * p_world;
  if (!(q.z() > 0.0)) return false;
  *uv = Eigen::Vector2d(k.fx * q.x() / q.z() + k.cx, k.fy * q.y() / q.z() + k.cy);
  return true;
}

}  // namespace hameritt::render
