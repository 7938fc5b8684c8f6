#pragma once
// Conversions between the simulator core's types and ROS messages, in one place.

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Imu.h>

#include "hameritt/BoundingBoxArray.h"
#include "hameritt/EntityState.h"
#include "hameritt/render/renderer.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/sim/simulator.h"

namespace hameritt::ros_wrappers {

// Frame names.
constexpr const char* kMapFrame = "map";
constexpr const char* kBaseFrame = "uav/base_link";

// Odometry of the UAV: pose in map, twist in the body frame (REP 105 / nav_msgs convention).
nav_msgs::Odometry toOdometryMsg(const sim::UavState& s, const ros::Time& stamp);
// IMU reading: orientation, body rates and specific force in the body frame.
sensor_msgs::Imu toImuMsg(const sim::UavState& s, const ros::Time& stamp);
// map -> uav/base_link.
geometry_msgs::TransformStamped toBaseTransform(const sim::UavState& s, const ros::Time& stamp);
// uav/base_link -> uav/<camera>_link from a payload camera's mount (FLU, rpy in degrees).
geometry_msgs::TransformStamped toCameraTransform(const scenario::CameraSpec& c, const ros::Time& stamp);
// Ground truth of one entity.
hameritt::EntityState toMsg(const sim::EntityState& e, const ros::Time& stamp);
// map -> <entity id>.
geometry_msgs::TransformStamped toEntityTransform(const sim::EntityState& e, const ros::Time& stamp);

// Camera intrinsics as sensor_msgs/CameraInfo (plumb_bob with zero distortion, R = I,
// P = [K | 0]): projecting with K lands exactly where the renderer draws.
sensor_msgs::CameraInfo toCameraInfoMsg(const render::Intrinsics& k, const std_msgs::Header& header);
// The boxes of one camera frame.
hameritt::BoundingBoxArray toBoxesMsg(const std::vector<render::BoundingBox>& boxes,
                                      const std::string& camera, const std_msgs::Header& header);
// A static transform (parent -> child) from an isometry.
geometry_msgs::TransformStamped toTransformMsg(const Eigen::Isometry3d& t, const std::string& parent,
                                               const std::string& child, const ros::Time& stamp);

// A trajectory pose (position and yaw) as a pose in map stamped `stamp`: what setpoints on
// uav/cmd_pose and the poses of a timed path are.
geometry_msgs::PoseStamped toPoseMsg(const scenario::TrajectoryPoint& p, const ros::Time& stamp);

// A timed path as nav_msgs/Path in map: each pose stamped with its sim time, yaw-only.
nav_msgs::Path toPathMsg(const scenario::Trajectory& path, const ros::Time& stamp);

}  // namespace hameritt::ros_wrappers
