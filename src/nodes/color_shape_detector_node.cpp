// color_shape_detector: colour/shape car detector with symbolic-context confuser rejection
// (baseline perception client).
#include <ros/ros.h>

#include "hameritt/ros/color_shape_detector_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "color_shape_detector");
  ros::NodeHandle nh, pnh("~");
  std::unique_ptr<hameritt::ros_wrappers::ColorShapeDetectorRos> node;
  try {
    node = std::make_unique<hameritt::ros_wrappers::ColorShapeDetectorRos>(nh, pnh);
  } catch (const std::exception& e) {
    ROS_FATAL("color_shape_detector: %s", e.what());
    return 1;
  }
  node->spin();
  return 0;
}
