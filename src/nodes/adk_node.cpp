// adk: mission API, constraint monitor, perfect perception, detection scoring and metrics
// (see docs/explanation/adk.md).
#include <ros/ros.h>

#include <csignal>

#include "hameritt/ros/adk_ros.h"

int main(int argc, char** argv) {
  // The node ends a mission cut short as "aborted" and still writes its metrics: it handles
  // SIGINT and SIGTERM itself instead of letting roscpp shut down at once.
  ros::init(argc, argv, "adk", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, [](int) { hameritt::ros_wrappers::AdkRos::requestStop(); });
  std::signal(SIGTERM, [](int) { hameritt::ros_wrappers::AdkRos::requestStop(); });
  ros::NodeHandle nh, pnh("~");
  std::unique_ptr<hameritt::ros_wrappers::AdkRos> node;
  try {
    node = std::make_unique<hameritt::ros_wrappers::AdkRos>(nh, pnh);
  } catch (const std::exception& e) {
    ROS_FATAL("adk: %s", e.what());
    return 1;
  }
  return node->spin();
}
