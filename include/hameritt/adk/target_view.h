#pragma once
// Ground truth of the track mission's targets that the renderer gives no box for. The renderer
// boxes a target only when at least one of its pixels shows; a target hidden behind a building
// or a tree inside the camera's view has none. Here its 3D extent is projected into the image:
// in view, it is a frame at occlusion level "full" (visible fraction 0), not tracked; out of
// view, it stays out of the frame's truth (TargetTrackingScore counts it in `frames` but not
// in `in_view_frames`). ROS-free.

#include <Eigen/Geometry>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hameritt/adk/coverage.h"  // CameraIntrinsics
#include "hameritt/adk/tracking_metrics.h"
#include "hameritt/geometry/oriented_box.h"

namespace hameritt::adk {

// What counts as inside the camera's view.
struct ViewLimits {
  double near_clip = 0.1;    // m, the renderer's near plane
  double far_clip = 2000.0;  // m along the optical axis, the renderer's far plane
  // A projection narrower or lower than this (pixels, after clipping to the image) is out of
  // view: at that size the renderer may draw none of the car's pixels even with nothing in
  // front of it, so a missing box says nothing about an occluder.
  double min_side_px = 3.0;
};

// A 3D box seen by a pinhole camera.
struct BoxProjection {
  bool in_view = false;
  // The bounds of the box's projection clipped to the image, in the renderer's box convention
  // (pixel i spans [i, i + 1), so a box of columns x_min..x_max is {x_min, .., x_max - x_min +
  // 1, ..}); empty when the box is not in view.
  PixelBox box;
};

// Projects `box` (world frame) into a camera at world_T_optical (z forward, x right, y down)
// with intrinsics k: the part of the box in front of the near plane, its bounds clipped to the
// image. In view when that part exists, some of it lies within far_clip along the optical
// axis, and its clipped bounds are at least min_side_px on each side.
BoxProjection projectBox(const CameraIntrinsics& k, const Eigen::Isometry3d& world_T_optical,
                         const geometry::OrientedBox& box, const ViewLimits& limits = {});

// A mission target's 3D extent at a frame's time.
struct TargetExtent {
  std::string id;
  geometry::OrientedBox box;
};

// One frame's ground truth of the mission targets: `rendered` (the targets the renderer boxed,
// kept as they are) plus, for each target of `targets` absent from it whose extent is in view,
// its projected box at occlusion 1 and visible fraction 0. Targets out of view stay absent.
std::vector<TargetTruth> withHiddenTargets(std::vector<TargetTruth> rendered,
                                           const std::vector<TargetExtent>& targets,
                                           const CameraIntrinsics& k,
                                           const Eigen::Isometry3d& world_T_optical,
                                           const ViewLimits& limits = {});

// Recent poses by time (the UAV's odometry), so that a camera frame stamped a little in the
// past is placed where the UAV was then.
class PoseHistory {
 public:
  // Keeps `horizon` seconds of poses before the newest.
  explicit PoseHistory(double horizon = 5.0) : horizon_(horizon) {}
  // A pose at t; one not after the newest is ignored.
  void add(double t, const Eigen::Isometry3d& pose);
  // The pose at t: interpolated between the poses either side (position linearly, rotation by
  // slerp), or the nearest when t lies outside them by at most max_gap seconds; none otherwise.
  std::optional<Eigen::Isometry3d> at(double t, double max_gap = 0.25) const;

 private:
  double horizon_;
  std::deque<std::pair<double, Eigen::Isometry3d>> poses_;
};

}  // namespace hameritt::adk
