// coverage_search_client: prior-weighted coverage search of the mission's areas through the
// planner's waypoint follower (baseline maneuver client).
#include <ros/ros.h>

#include "hameritt/ros/coverage_search_client_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "coverage_search_client");
  ros::NodeHandle nh, pnh("~");
  std::unique_ptr<hameritt::ros_wrappers::CoverageSearchClientRos> node;
  try {
    node = std::make_unique<hameritt::ros_wrappers::CoverageSearchClientRos>(nh, pnh);
  } catch (const std::exception& e) {
    ROS_FATAL("coverage_search_client: %s", e.what());
    return 1;
  }
  node->spin();
  return 0;
}
