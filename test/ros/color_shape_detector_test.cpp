// rostest: color_shape_detector turns camera frames into claims. The test node publishes sim time,
// the mission, tf (map -> uav/base_link, uav/base_link -> uav/camera_down_optical), camera_info
// and matching rgb8 / 32FC1 frames of a synthetic scene at the shipped scenario's target: the
// white RAV4 at the target's place is claimed once (the same frame again is no new claim), the
// same car 11 m down the street (not next to the target's tree) never.
#include "hameritt/build_paths.h"
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <cstring>

#include "../clients/synthetic_scene.h"
#include "hameritt/Detection.h"
#include "hameritt/clients/color_detector.h"
#include "hameritt/clients/public_config.h"
#include "hameritt/ros/mission_conversions.h"
#include "hameritt/scenario/mission_io.h"

namespace {

using hameritt::geometry::Vec3;
namespace clients = hameritt::clients;

const std::string kScenario = std::string(HAMERITT_SOURCE_DIR) + "/scenarios/default/";

geometry_msgs::TransformStamped transform(const Eigen::Isometry3d& x, const std::string& parent,
                                          const std::string& child, const ros::Time& stamp) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.x = x.translation().x();
  t.transform.translation.y = x.translation().y();
  t.transform.translation.z = x.translation().z();
  const Eigen::Quaterniond q(x.linear());
  t.transform.rotation.x = q.x();
  t.transform.rotation.y = q.y();
  t.transform.rotation.z = q.z();
  t.transform.rotation.w = q.w();
  return t;
}

TEST(ColorShapeDetector, ClaimsTheTargetOnceAndNeverItsLookAlike) {
  ros::NodeHandle nh;
  ros::Publisher clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  ros::Publisher mission_pub = nh.advertise<hameritt::Mission>("/mission", 1, true);
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/uav/camera/down/image_raw", 2);
  ros::Publisher depth_pub = nh.advertise<sensor_msgs::Image>("/uav/camera/down/depth", 2);
  ros::Publisher info_pub =
      nh.advertise<sensor_msgs::CameraInfo>("/uav/camera/down/camera_info", 2, true);
  std::vector<hameritt::Detection> detections;
  ros::Subscriber det_sub = nh.subscribe<hameritt::Detection>(
      "/perception/detections", 20,
      [&](const hameritt::Detection::ConstPtr& d) { detections.push_back(*d); });
  tf2_ros::TransformBroadcaster tf_pub;
  tf2_ros::StaticTransformBroadcaster tf_static;

  double now = 100.0;  // inside aoi_1's window [48, 192]
  auto tick = [&](double wall) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(wall);
    while (ros::ok() && ros::WallTime::now() < until) {
      rosgraph_msgs::Clock c;
      c.clock = ros::Time(now);
      clock_pub.publish(c);
      ros::spinOnce();
      ros::WallDuration(0.01).sleep();
    }
  };
  tick(0.5);
  mission_pub.publish(
      hameritt::ros_wrappers::toMsg(hameritt::scenario::loadMission(kScenario + "mission.json")));
  const ros::WallTime up = ros::WallTime::now() + ros::WallDuration(30);
  while ((image_pub.getNumSubscribers() == 0 || depth_pub.getNumSubscribers() == 0 ||
          det_sub.getNumPublishers() == 0) &&
         ros::WallTime::now() < up) {
    tick(0.05);
  }
  ASSERT_GT(image_pub.getNumSubscribers(), 0u) << "color_shape_detector is not up";
  tick(1.0);  // the mission reaches the detector

  // The down camera of the shipped scenario, 38 m over the street next to the target.
  const auto sim = clients::loadPublicSimConfig(kScenario + "sim_config.json");
  const hameritt::scenario::CameraSpec* down = nullptr;
  for (const auto& c : sim.uav.cameras) {
    if (c.name == "down") down = &c;
  }
  ASSERT_NE(down, nullptr);
  const clients::PinholeCamera cam =
      clients::pinholeFromHfov(down->width, down->height, down->hfov_deg);
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() = Vec3(-271.039 + 5.0, 248.982, 38.0);
  const Eigen::Isometry3d optical = clients::opticalPose(base, down->mount_xyz, down->mount_rpy);
  const cv::Vec3b white(235, 236, 238), asphalt(110, 110, 112);
  const auto frame = clients::testing::renderFrame(
      cam, optical,
      {clients::testing::car(-271.039, 248.982, 3.137, 4.6, 1.855, 1.685, white),
       clients::testing::car(-271.039 + 11.0, 249.082, 3.137, 4.6, 1.855, 1.685, white)},
      asphalt);
  tf_static.sendTransform(transform(base.inverse() * optical, "uav/base_link",
                                    "uav/camera_down_optical", ros::Time(0)));

  auto publishFrame = [&](double t) {
    const ros::Time stamp(t);
    tf_pub.sendTransform(transform(base, "map", "uav/base_link", stamp));
    sensor_msgs::CameraInfo info;
    info.header.stamp = stamp;
    info.header.frame_id = "uav/camera_down_optical";
    info.width = cam.width;
    info.height = cam.height;
    info.K = {cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1};
    info.P = {cam.fx, 0, cam.cx, 0, 0, cam.fy, cam.cy, 0, 0, 0, 1, 0};
    info_pub.publish(info);
    sensor_msgs::Image img;
    img.header = info.header;
    img.width = cam.width;
    img.height = cam.height;
    img.encoding = "rgb8";
    img.step = cam.width * 3;
    img.data.assign(frame.rgb.data, frame.rgb.data + frame.rgb.total() * 3);
    sensor_msgs::Image depth = img;
    depth.encoding = "32FC1";
    depth.step = cam.width * 4;
    depth.data.resize(static_cast<std::size_t>(depth.step) * depth.height);
    std::memcpy(depth.data.data(), frame.depth.data, depth.data.size());
    tick(0.2);  // tf and camera_info first
    image_pub.publish(img);
    depth_pub.publish(depth);
  };

  publishFrame(now);
  const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(20);
  while (detections.empty() && ros::WallTime::now() < until) tick(0.05);
  ASSERT_EQ(detections.size(), 1u) << "no claim";
  // The same place a second later: not a new claim.
  now += 1.0;
  publishFrame(now);
  tick(2.0);
  ASSERT_EQ(detections.size(), 1u);
  const hameritt::Detection& d = detections.front();
  EXPECT_EQ(d.client, "color_shape_detector");
  EXPECT_EQ(d.description, "white Toyota RAV4 (suv)");
  EXPECT_EQ(d.entity_class, "car");
  EXPECT_EQ(d.header.stamp, ros::Time(100.0));
  EXPECT_EQ(d.header.frame_id, "map");
  EXPECT_LT(std::hypot(d.position.x + 271.039, d.position.y - 248.982), 0.5);
  EXPECT_GT(d.confidence, 0.5f);
  EXPECT_LE(d.confidence, 1.0f);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "color_shape_detector_test");
  return RUN_ALL_TESTS();
}
