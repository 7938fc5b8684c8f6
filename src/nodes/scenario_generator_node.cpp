// scenario_generator: offers random scenario generation as the ~generate service.
#include <ros/ros.h>

#include "hameritt/ros/scenario_generator_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "scenario_generator");
  ros::NodeHandle nh("~");
  std::unique_ptr<hameritt::ros_wrappers::ScenarioGeneratorRos> node;
  try {
    node = std::make_unique<hameritt::ros_wrappers::ScenarioGeneratorRos>(nh);
  } catch (const std::exception& e) {
    ROS_FATAL("scenario_generator: %s", e.what());
    return 1;
  }
  ros::spin();
  return 0;
}
