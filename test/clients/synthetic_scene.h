#pragma once
// Synthetic camera frames for the detector tests: a flat ground of one colour with flat-topped
// coloured boxes standing on it (car bodies seen from above), rendered by ray casting into an
// RGB image and an exact depth image (metres along the optical axis) for a known pinhole camera
// and pose. Deterministic; no renderer needed.

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <vector>

#include "hameritt/clients/color_detector.h"
#include "hameritt/geometry/oriented_box.h"

namespace hameritt::clients::testing {

struct ColoredBox {
  geometry::OrientedBox box;
  cv::Vec3b rgb;
};

struct Frame {
  cv::Mat rgb;    // CV_8UC3, R first
  cv::Mat depth;  // CV_32FC1
};

// Casts one ray per pixel centre. Boxes are hit on their top face only (a nadir view sees
// nothing else of a car); the ground is the plane z = 0.
inline Frame renderFrame(const PinholeCamera& cam, const Eigen::Isometry3d& world_T_optical,
                         const std::vector<ColoredBox>& boxes, const cv::Vec3b& ground) {
  Frame f;
  f.rgb = cv::Mat(cam.height, cam.width, CV_8UC3, cv::Scalar(ground[0], ground[1], ground[2]));
  f.depth =
      cv::Mat(cam.height, cam.width, CV_32FC1, cv::Scalar(std::numeric_limits<float>::infinity()));
  const Eigen::Matrix3d R = world_T_optical.linear();
  const Eigen::Vector3d o = world_T_optical.translation();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      // Ray direction with optical z = 1: the ray parameter is the depth.
      const Eigen::Vector3d d =
          R * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1);
      double best = std::numeric_limits<double>::infinity();
      cv::Vec3b colour = ground;
      if (d.z() < -1e-9) {
        const double t = -o.z() / d.z();
        if (t > 0) best = t;
      }
      for (const auto& b : boxes) {
        if (d.z() >= -1e-9) continue;
        const double t = (b.box.maxZ() - o.z()) / d.z();
        if (t <= 0 || t >= best) continue;
        const Eigen::Vector3d p = o + t * d;
        if (b.box.footprint().contains(p.head<2>())) {
          best = t;
          colour = b.rgb;
        }
      }
      if (std::isfinite(best)) {
        f.rgb.at<cv::Vec3b>(v, u) = colour;
        f.depth.at<float>(v, u) = static_cast<float>(best);
      }
    }
  }
  return f;
}

// A nadir camera (the down camera's mount: pitch 90 deg) on a UAV at `position` with `yaw`.
inline Eigen::Isometry3d nadirCamera(const Eigen::Vector3d& position, double yaw) {
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() = position;
  base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return opticalPose(base, Eigen::Vector3d(0, 0, -0.06), Eigen::Vector3d(0, 90, 0));
}

// A car body: footprint length x width, top at `height`, bottom-centre (x, y) on the ground.
inline ColoredBox car(double x, double y, double yaw, double length, double width, double height,
                      const cv::Vec3b& rgb) {
  ColoredBox c;
  c.box.center = Eigen::Vector3d(x, y, 0.5 * height);
  c.box.size = Eigen::Vector3d(length, width, height);
  c.box.yaw = yaw;
  c.rgb = rgb;
  return c;
}

}  // namespace hameritt::clients::testing
