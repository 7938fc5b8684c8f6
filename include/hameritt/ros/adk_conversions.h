#pragma once
// Conversions between the ADK core's and the scenario's types and the ADK's ROS messages, in
// one place.

#include <nav_msgs/Odometry.h>
#include <visualization_msgs/MarkerArray.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "hameritt/ConstraintEvent.h"
#include "hameritt/ConstraintStatus.h"
#include "hameritt/Detection.h"
#include "hameritt/EntityStateArray.h"
#include "hameritt/KeyValue.h"
#include "hameritt/KozViolation.h"
#include "hameritt/Mission.h"
#include "hameritt/MissionMetrics.h"
#include "hameritt/adk/constraint_monitor.h"
#include "hameritt/adk/detection_scoring.h"
#include "hameritt/adk/metrics.h"
#include "hameritt/ros/mission_conversions.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::ros_wrappers {

// The mission description as a message (frame map). Carries exactly what mission.json says,
// never a target's position.
hameritt::Mission toMsg(const scenario::Mission& m, const ros::Time& stamp);

// RViz markers of the mission in frame map: AOI outlines (ns "aoi"), keep-out prisms as edges
// ("koz") and translucent walls ("koz_walls"), prior cells shaded by probability ("prior"),
// route polylines ("route") and band outlines ("route_band"), and labels ("label"). An open
// altitude bound is drawn at 0 m (below) or `open_top` m (above).
visualization_msgs::MarkerArray missionMarkers(const scenario::Mission& m, double open_top,
                                               const ros::Time& stamp);

hameritt::KozViolation toMsg(const adk::Violation& v);
hameritt::ConstraintStatus toMsg(const adk::ConstraintMonitor& monitor, const ros::Time& stamp);
hameritt::ConstraintEvent toMsg(const adk::ConstraintEvent& e);
hameritt::MissionMetrics toMsg(const adk::MissionMetrics& m, const std::string& metrics_file,
                               const ros::Time& stamp);

// A detection claim (its stamp, class, position and confidence).
adk::DetectionClaim fromMsg(const hameritt::Detection& d);
// Ground truth of the simulator's entities (bottom-face centre, yaw from the orientation).
std::vector<adk::EntityTruth> fromMsg(const hameritt::EntityStateArray& a);

// Odometry pose as world_T_base, and the velocity in the world frame (the twist is in the
// body frame).
Eigen::Isometry3d poseOf(const nav_msgs::Odometry& o);
Eigen::Vector3d worldVelocityOf(const nav_msgs::Odometry& o);

}  // namespace hameritt::ros_wrappers
