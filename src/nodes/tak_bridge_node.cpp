// tak_bridge: the COP, the UAV and the mission's zones as Cursor-on-Target events to TAK
// (see docs/explanation/cop.md).
#include <ros/ros.h>

#include <memory>

#include "hameritt/ros/cop_ros.h"
#include "hameritt/ros/tak_bridge_ros.h"

int main(int argc, char** argv) {
  // Its own signal handling: the summary is logged before roscpp shuts down.
  ros::init(argc, argv, "tak_bridge", ros::init_options::NoSigintHandler);
  ros::NodeHandle nh, pnh("~");
  std::unique_ptr<hameritt::ros_wrappers::TakBridgeRos> node;
  try {
    node = std::make_unique<hameritt::ros_wrappers::TakBridgeRos>(nh, pnh);
  } catch (const std::exception& e) {
    ROS_FATAL("tak_bridge: %s", e.what());
    return 1;
  }
  hameritt::ros_wrappers::spinUntilSignal();
  node->logSummary();
  ros::shutdown();
  return 0;
}
