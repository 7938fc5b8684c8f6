// Intrinsics, camera mounts and the pinhole projection conventions (ROS / OpenCV).

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <random>

#include "render_test_util.h"

namespace hameritt::render {
namespace {

TEST(RenderCamera, IntrinsicsFromHfov) {
  const Intrinsics k = intrinsicsFromHfov(640, 480, 90.0);
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 480);
  EXPECT_NEAR(k.fx, 320.0, 1e-9);
  EXPECT_EQ(k.fx, k.fy);
  EXPECT_DOUBLE_EQ(k.cx, 319.5);
  EXPECT_DOUBLE_EQ(k.cy, 239.5);
  const Intrinsics n = intrinsicsFromHfov(101, 37, 60.0);
  EXPECT_NEAR(n.fx, 50.5 / std::tan(M_PI / 6.0), 1e-9);
  EXPECT_DOUBLE_EQ(n.cx, 50.0);
  EXPECT_DOUBLE_EQ(n.cy, 18.0);
}

TEST(RenderCamera, IntrinsicsRejectBadSizesAndFieldsOfView) {
  auto message = [](auto f) {
    try {
      f();
    } catch (const RenderError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([] { intrinsicsFromHfov(0, 480, 90); }).find("width and height"),
            std::string::npos);
  EXPECT_NE(message([] { intrinsicsFromHfov(640, -1, 90); }).find("width and height"),
            std::string::npos);
  EXPECT_NE(message([] { intrinsicsFromHfov(640, 480, 0); }).find("hfov_deg"), std::string::npos);
  EXPECT_NE(message([] { intrinsicsFromHfov(640, 480, 180); }).find("got 180"), std::string::npos);
  EXPECT_NE(message([] { intrinsicsFromHfov(640, 480, NAN); }).find("hfov_deg"), std::string::npos);
  EXPECT_NO_THROW(intrinsicsFromHfov(1, 1, 179.9));
}

TEST(RenderCamera, OpticalPoseConventions) {
  const Eigen::Isometry3d base = testing::uavPose(10, 20, 30, M_PI / 2);  // heading north
  // Level front camera: optical z = body forward (north), x = body right (east), y = down.
  const Eigen::Isometry3d front = opticalPose(base, {0.12, 0, -0.03}, {0, 0, 0});
  EXPECT_TRUE(front.linear().col(2).isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));
  EXPECT_TRUE(front.linear().col(0).isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
  EXPECT_TRUE(front.linear().col(1).isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
  EXPECT_TRUE(front.translation().isApprox(Eigen::Vector3d(10, 20.12, 29.97), 1e-12));
  // Pitch 90 deg looks down: optical z = -world z on a level UAV; image up = forward.
  const Eigen::Isometry3d down = opticalPose(base, {0, 0, -0.06}, {0, M_PI / 2, 0});
  EXPECT_TRUE(down.linear().col(2).isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
  EXPECT_TRUE(down.linear().col(1).isApprox(Eigen::Vector3d(0, -1, 0), 1e-12));
  // Positive pitch tilts the view below the horizon.
  const Eigen::Isometry3d tilted = opticalPose(base, {0, 0, 0}, {0, 0.2, 0});
  EXPECT_NEAR(tilted.linear().col(2).z(), -std::sin(0.2), 1e-12);
}

TEST(RenderCamera, ProjectionAgreesWithOpenCv) {
  const Intrinsics k = intrinsicsFromHfov(640, 480, 94.321);
  const Eigen::Isometry3d pose = testing::lookAt({3, -4, 40}, {30, 25, 0});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> d(-60, 60);
  std::vector<cv::Point3d> object;
  std::vector<Eigen::Vector2d> ours;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p(30 + d(rng), 25 + d(rng), 0.1 * std::abs(d(rng)));
    Eigen::Vector2d uv;
    if (!projectPoint(k, pose, p, &uv)) continue;
    object.emplace_back(p.x(), p.y(), p.z());
    ours.push_back(uv);
  }
  ASSERT_GT(object.size(), 100u);
  // OpenCV: rvec, tvec map world to the camera (optical) frame.
  const Eigen::Isometry3d optical_T_world = pose.inverse();
  cv::Mat rot(3, 3, CV_64F), rvec, tvec(3, 1, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rot.at<double>(r, c) = optical_T_world.linear()(r, c);
    tvec.at<double>(r) = optical_T_world.translation()(r);
  }
  cv::Rodrigues(rot, rvec);
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  std::vector<cv::Point2d> theirs;
  cv::projectPoints(object, rvec, tvec, K, cv::noArray(), theirs);
  for (std::size_t i = 0; i < theirs.size(); ++i) {
    EXPECT_NEAR(theirs[i].x, ours[i].x(), 1e-6);
    EXPECT_NEAR(theirs[i].y, ours[i].y(), 1e-6);
  }
  Eigen::Vector2d uv;
  EXPECT_FALSE(projectPoint(k, pose, pose * Eigen::Vector3d(0, 0, -1), &uv)) << "behind the camera";
}

}  // namespace
}  // namespace hameritt::render
