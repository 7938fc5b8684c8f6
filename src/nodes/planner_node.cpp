// planner: PlanPath service and waypoint follower over the planning library.
#include <ros/ros.h>

#include "hameritt/ros/planner_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "planner");
  ros::NodeHandle nh, pnh("~");
  std::unique_ptr<hameritt::ros_wrappers::PlannerRos> node;
  try {
    node = std::make_unique<hameritt::ros_wrappers::PlannerRos>(nh, pnh);
  } catch (const std::exception& e) {
    ROS_FATAL("planner: %s", e.what());
    return 1;
  }
  node->spin();
  return 0;
}
