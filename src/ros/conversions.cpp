#include "hameritt/ros/conversions.h"

#include <cmath>

namespace hameritt::ros_wrappers {

namespace {

geometry_msgs::Quaternion toQuat(const Eigen::Quaterniond& q) {
  geometry_msgs::Quaternion m;
  m.x = q.x();
  m.y = q.y();
  m.z = q.z();
  m.w = q.w();
  return m;
}

geometry_msgs::Quaternion yawQuat(double yaw) {
  return toQuat(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())));
}

}  // namespace

nav_msgs::Odometry toOdometryMsg(const sim::UavState& s, const ros::Time& stamp) {
  nav_msgs::Odometry m;
  m.header.stamp = stamp;
  m.header.frame_id = kMapFrame;
  m.child_frame_id = kBaseFrame;
  m.pose.pose.position.x = s.position.x();
  m.pose.pose.position.y = s.position.y();
  m.pose.pose.position.z = s.position.z();
  m.pose.pose.orientation = toQuat(s.orientation);
  const Eigen::Vector3d v_body = s.orientation.conjugate() * s.velocity;
  m.twist.twist.linear.x = v_body.x();
  m.twist.twist.linear.y = v_body.y();
  m.twist.twist.linear.z = v_body.z();
  m.twist.twist.angular.x = s.angular_velocity.x();
  m.twist.twist.angular.y = s.angular_velocity.y();
  m.twist.twist.angular.z = s.angular_velocity.z();
  return m;
}

sensor_msgs::Imu toImuMsg(const sim::UavState& s, const ros::Time& stamp) {
  sensor_msgs::Imu m;
  m.header.stamp = stamp;
  m.header.frame_id = kBaseFrame;
  m.orientation = toQuat(s.orientation);
  m.angular_velocity.x = s.angular_velocity.x();
  m.angular_velocity.y = s.angular_velocity.y();
  m.angular_velocity.z = s.angular_velocity.z();
  m.linear_acceleration.x = s.specific_force.x();
  m.linear_acceleration.y = s.specific_force.y();
  m.linear_acceleration.z = s.specific_force.z();
  return m;
}

geometry_msgs::TransformStamped toBaseTransform(const sim::UavState& s, const ros::Time& stamp) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = kMapFrame;
  t.child_frame_id = kBaseFrame;
  t.transform.translation.x = s.position.x();
  t.transform.translation.y = s.position.y();
  t.transform.translation.z = s.position.z();
  t.transform.rotation = toQuat(s.orientation);
  return t;
}

geometry_msgs::TransformStamped toCameraTransform(const scenario::CameraSpec& c,
                                                  const ros::Time& stamp) {
  constexpr double kDeg = M_PI / 180.0;
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = kBaseFrame;
  t.child_frame_id = "uav/" + c.name + "_camera_link";
  t.transform.translation.x = c.mount_xyz.x();
  t.transform.translation.y = c.mount_xyz.y();
  t.transform.translation.z = c.mount_xyz.z();
  const Eigen::Quaterniond q = Eigen::AngleAxisd(c.mount_rpy.z() * kDeg, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(c.mount_rpy.y() * kDeg, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(c.mount_rpy.x() * kDeg, Eigen::Vector3d::UnitX());
  t.transform.rotation = toQuat(q);
  return t;
}

hameritt::EntityState toMsg(const sim::EntityState& e, const ros::Time& stamp) {
  hameritt::EntityState m;
  m.header.stamp = stamp;
  m.header.frame_id = kMapFrame;
  m.id = e.id;
  m.entity_class = scenario::toString(e.cls);
  m.role = e.role;
  m.pose.position.x = e.box.center.x();
  m.pose.position.y = e.box.center.y();
  m.pose.position.z = e.box.minZ();
  m.pose.orientation = yawQuat(e.box.yaw);
  m.velocity.linear.x = e.velocity.x();
  m.velocity.linear.y = e.velocity.y();
  m.velocity.linear.z = e.velocity.z();
  m.velocity.angular.z = e.yaw_rate;
  m.size.x = e.box.size.x();
  m.size.y = e.box.size.y();
  m.size.z = e.box.size.z();
  return m;
}

geometry_msgs::TransformStamped toEntityTransform(const sim::EntityState& e, const ros::Time& stamp) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = kMapFrame;
  t.child_frame_id = e.id;
  t.transform.translation.x = e.box.center.x();
  t.transform.translation.y = e.box.center.y();
  t.transform.translation.z = e.box.minZ();
  t.transform.rotation = yawQuat(e.box.yaw);
  return t;
}

geometry_msgs::PoseStamped toPoseMsg(const scenario::TrajectoryPoint& p, const ros::Time& stamp) {
  geometry_msgs::PoseStamped ps;
  ps.header.stamp = stamp;
  ps.header.frame_id = kMapFrame;
  ps.pose.position.x = p.x;
  ps.pose.position.y = p.y;
  ps.pose.position.z = p.z;
  ps.pose.orientation = yawQuat(p.yaw);
  return ps;
}

nav_msgs::Path toPathMsg(const scenario::Trajectory& path, const ros::Time& stamp) {
  nav_msgs::Path m;
  m.header.stamp = stamp;
  m.header.frame_id = kMapFrame;
  m.poses.reserve(path.size());
  for (const auto& p : path) m.poses.push_back(toPoseMsg(p, ros::Time(p.t)));
  return m;
}

sensor_msgs::CameraInfo toCameraInfoMsg(const render::Intrinsics& k, const std_msgs::Header& header) {
  sensor_msgs::CameraInfo m;
  m.header = header;
  m.width = static_cast<std::uint32_t>(k.width);
  m.height = static_cast<std::uint32_t>(k.height);
  m.distortion_model = "plumb_bob";
  m.D.assign(5, 0.0);
  m.K = {k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0};
  m.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  m.P = {k.fx, 0.0, k.cx, 0.0, 0.0, k.fy, k.cy, 0.0, 0.0, 0.0, 1.0, 0.0};
  return m;
}

hameritt::BoundingBoxArray toBoxesMsg(const std::vector<render::BoundingBox>& boxes,
                                      const std::string& camera, const std_msgs::Header& header) {
  hameritt::BoundingBoxArray m;
  m.header = header;
  m.camera = camera;
  m.boxes.reserve(boxes.size());
  for (const auto& b : boxes) {
    hameritt::BoundingBox o;
    o.entity_id = b.entity_id;
    o.entity_class = scenario::toString(b.cls);
    o.role = b.role;
    o.instance_id = static_cast<std::uint16_t>(b.instance);
    o.x_min = b.x_min;
    o.y_min = b.y_min;
    o.x_max = b.x_max;
    o.y_max = b.y_max;
    o.visible_pixels = static_cast<std::uint32_t>(b.visible_pixels);
    o.total_pixels = static_cast<std::uint32_t>(b.total_pixels);
    o.occlusion = static_cast<float>(b.occlusion);
    m.boxes.push_back(std::move(o));
  }
  return m;
}

geometry_msgs::TransformStamped toTransformMsg(const Eigen::Isometry3d& t, const std::string& parent,
                                               const std::string& child, const ros::Time& stamp) {
  geometry_msgs::TransformStamped m;
  m.header.stamp = stamp;
  m.header.frame_id = parent;
  m.child_frame_id = child;
  m.transform.translation.x = t.translation().x();
  m.transform.translation.y = t.translation().y();
  m.transform.translation.z = t.translation().z();
  m.transform.rotation = toQuat(Eigen::Quaterniond(t.linear()));
  return m;
}

}  // namespace hameritt::ros_wrappers
