// path_player: flies the sim_config's perception-only path (uav.perception_path, the safe
// look-at path the generator planned) by publishing its pose at the current sim time (plus a
// small lead) as setpoints on uav/cmd_pose. Used by mission.launch mode:=perception_only.
#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>

#include "hameritt/ros/conversions.h"
#include "hameritt/ros/lockstep.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/sim_config_io.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "path_player");
  ros::NodeHandle nh, pnh("~");
  std::string sim_config;
  double rate_hz = 20.0, lead = 0.3;
  pnh.param("rate_hz", rate_hz, rate_hz);
  pnh.param("lead", lead, lead);
  hameritt::scenario::Trajectory path;
  try {
    if (!pnh.getParam("sim_config", sim_config)) {
      throw std::runtime_error("~sim_config: required parameter (path of a sim_config.json)");
    }
    if (!(rate_hz > 0 && rate_hz <= 1000)) throw std::runtime_error("~rate_hz: expected (0, 1000]");
    if (!(lead >= 0 && lead <= 5)) throw std::runtime_error("~lead: expected [0, 5] seconds");
    const auto config = hameritt::scenario::loadSimConfig(sim_config);
    if (!config.uav.perception_path || config.uav.perception_path->trajectory.size() < 2) {
      throw std::runtime_error(sim_config +
                               ": uav.perception_path: absent or empty (generate the "
                               "scenario with \"perception_paths\": true)");
    }
    path = config.uav.perception_path->trajectory;
    ROS_INFO("path_player: %zu poses, %.1f s, status %s, camera %s", path.size(), path.back().t,
             config.uav.perception_path->status.c_str(),
             config.uav.perception_path->camera.c_str());
  } catch (const std::exception& e) {
    ROS_FATAL("path_player: %s", e.what());
    return 1;
  }
  std::unique_ptr<hameritt::ros_wrappers::LockstepGate> gate;
  try {
    gate = std::make_unique<hameritt::ros_wrappers::LockstepGate>(nh, pnh);
  } catch (const std::exception& e) {
    ROS_FATAL("path_player: %s", e.what());
    return 1;
  }
  ros::Publisher pub = gate->advertise<geometry_msgs::PoseStamped>(nh, "uav/cmd_pose", 10);
  gate->every(nh, 1.0 / rate_hz, [&] {
    const double t = ros::Time::now().toSec();
    if (t <= 0) return;  // no /clock yet
    gate->publish(pub, hameritt::ros_wrappers::toPoseMsg(
                           hameritt::scenario::sampleTrajectory(path, t + lead), ros::Time::now()));
  });
  gate->spin();
  return 0;
}
