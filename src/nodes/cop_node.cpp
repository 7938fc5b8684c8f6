// cop: the Common Operational Picture (track fusion of claims and perfect perception)
// (see docs/explanation/cop.md).
#include <ros/ros.h>

#include <memory>

#include "hameritt/ros/cop_ros.h"

int main(int argc, char** argv) {
  // Its own signal handling: the summary is logged before roscpp shuts down.
  ros::init(argc, argv, "cop", ros::init_options::NoSigintHandler);
  ros::NodeHandle nh, pnh("~");
  std::unique_ptr<hameritt::ros_wrappers::CopRos> node;
  try {
    node = std::make_unique<hameritt::ros_wrappers::CopRos>(nh, pnh);
  } catch (const std::exception& e) {
    ROS_FATAL("cop: %s", e.what());
    return 1;
  }
  hameritt::ros_wrappers::spinUntilSignal();
  node->logSummary();
  ros::shutdown();
  return 0;
}
