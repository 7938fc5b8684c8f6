#include "hameritt/adk/target_view.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace hameritt::adk {

BoxProjection projectBox(const CameraIntrinsics& k, const Eigen::Isometry3d& world_T_optical,
                         const geometry::OrientedBox& box, const ViewLimits& limits) {
  // The eight corners in the optical frame; corner c has bit 0 for +x (length), bit 1 for +y
  // (width), bit 2 for +z.
  const Eigen::Isometry3d optical_T_world = world_T_optical.inverse();
  const double c = std::cos(box.yaw), s = std::sin(box.yaw);
  std::array<Eigen::Vector3d, 8> q;
  for (int i = 0; i < 8; ++i) {
    const double bx = ((i & 1) ? 0.5 : -0.5) * box.size.x();
    const double by = ((i & 2) ? 0.5 : -0.5) * box.size.y();
    const double bz = ((i & 4) ? 0.5 : -0.5) * box.size.z();
    const Eigen::Vector3d w(box.center.x() + c * bx - s * by, box.center.y() + s * bx + c * by,
                            box.center.z() + bz);
    q[static_cast<std::size_t>(i)] = optical_T_world * w;
  }
  // The box's part in front of the near plane: its vertices are the corners in front and the
  // points where the 12 edges cross the plane.
  std::vector<Eigen::Vector3d> front;
  const double n = limits.near_clip;
  for (int a = 0; a < 8; ++a) {
    const Eigen::Vector3d& p = q[static_cast<std::size_t>(a)];
    if (p.z() >= n) front.push_back(p);
    for (int bit : {1, 2, 4}) {
      if (a & bit) continue;
      const Eigen::Vector3d& r = q[static_cast<std::size_t>(a | bit)];
      if ((p.z() >= n) != (r.z() >= n))
        front.push_back(p + (r - p) * ((n - p.z()) / (r.z() - p.z())));
    }
  }
  BoxProjection out;
  if (front.empty()) return out;
  double z_min = front[0].z();
  double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
  for (const auto& p : front) {
    z_min = std::min(z_min, p.z());
    // Pixel centres at integer (u, v); +0.5 puts pixel i at [i, i + 1).
    const double u = k.fx * p.x() / p.z() + k.cx + 0.5, v = k.fy * p.y() / p.z() + k.cy + 0.5;
    u0 = std::min(u0, u);
    u1 = std::max(u1, u);
    v0 = std::min(v0, v);
    v1 = std::max(v1, v);
  }
  if (z_min > limits.far_clip) return out;
  u0 = std::clamp(u0, 0.0, static_cast<double>(k.width));
  u1 = std::clamp(u1, 0.0, static_cast<double>(k.width));
  v0 = std::clamp(v0, 0.0, static_cast<double>(k.height));
  v1 = std::clamp(v1, 0.0, static_cast<double>(k.height));
  if (u1 - u0 < limits.min_side_px || v1 - v0 < limits.min_side_px) return out;
  out.in_view = true;
  out.box = PixelBox{u0, v0, u1 - u0, v1 - v0};
  return out;
}

std::vector<TargetTruth> withHiddenTargets(std::vector<TargetTruth> rendered,
                                           const std::vector<TargetExtent>& targets,
                                           const CameraIntrinsics& k,
                                           const Eigen::Isometry3d& world_T_optical,
                                           const ViewLimits& limits) {
  const std::size_t n = rendered.size();
  for (const auto& t : targets) {
    const auto end = rendered.begin() + static_cast<std::ptrdiff_t>(n);
    if (std::any_of(rendered.begin(), end, [&](const TargetTruth& g) { return g.id == t.id; })) {
      continue;
    }
    const BoxProjection p = projectBox(k, world_T_optical, t.box, limits);
    if (!p.in_view) continue;
    rendered.push_back(TargetTruth{t.id, p.box, 0.0, 1.0});
  }
  return rendered;
}

void PoseHistory::add(double t, const Eigen::Isometry3d& pose) {
  if (!poses_.empty() && !(t > poses_.back().first)) return;
  poses_.emplace_back(t, pose);
  while (poses_.size() > 2 && poses_.front().first < t - horizon_) poses_.pop_front();
}

std::optional<Eigen::Isometry3d> PoseHistory::at(double t, double max_gap) const {
  if (poses_.empty() || !std::isfinite(t)) return std::nullopt;
  if (t <= poses_.front().first) {
    if (poses_.front().first - t > max_gap) return std::nullopt;
    return poses_.front().second;
  }
  if (t >= poses_.back().first) {
    if (t - poses_.back().first > max_gap) return std::nullopt;
    return poses_.back().second;
  }
  const auto hi = std::lower_bound(poses_.begin(), poses_.end(), t,
                                   [](const auto& p, double v) { return p.first < v; });
  const auto lo = hi - 1;
  const double a = (t - lo->first) / (hi->first - lo->first);
  const Eigen::Quaterniond r0(lo->second.rotation()), r1(hi->second.rotation());
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = r0.slerp(a, r1).toRotationMatrix();
  pose.translation() = (1.0 - a) * lo->second.translation() + a * hi->second.translation();
  return pose;
}

}  // namespace hameritt::adk
