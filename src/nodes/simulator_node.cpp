// simulator: the physics of a scenario on sim time (see docs/explanation/simulator.md).
#include <ros/ros.h>

#include "hameritt/ros/simulator_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "simulator");
  ros::NodeHandle nh, pnh("~");
  std::unique_ptr<hameritt::ros_wrappers::SimulatorRos> node;
  try {
    node = std::make_unique<hameritt::ros_wrappers::SimulatorRos>(nh, pnh);
  } catch (const std::exception& e) {
    ROS_FATAL("simulator: %s", e.what());
    return 1;
  }
  node->spin();
  return 0;
}
