#pragma once
// ROS <-> core conversions used by the baseline clients: camera messages to OpenCV images and
// pinhole intrinsics, claims to hameritt/Detection, perfect-perception entities to observations,
// and the ADK's mission state from a message of any type.

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <topic_tools/shape_shifter.h>

#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "hameritt/Detection.h"
#include "hameritt/EntityState.h"
#include "hameritt/Mission.h"
#include "hameritt/PerceivedEntity.h"
#include "hameritt/clients/color_detector.h"
#include "hameritt/clients/context_filter.h"
#include "hameritt/clients/mission_state.h"
#include "hameritt/clients/pursuit.h"

namespace hameritt::ros_wrappers {

// An rgb8 or bgr8 image as CV_8UC3 in RGB order (copied). Throws scenario::ConfigError for
// other encodings or a bad size.
cv::Mat rgbFromMsg(const sensor_msgs::Image& msg);
// A 32FC1 (metres) or 16UC1 (millimetres, 0 = none) depth image as CV_32FC1 metres (copied;
// missing depth becomes +inf). Throws scenario::ConfigError for other encodings.
cv::Mat depthFromMsg(const sensor_msgs::Image& msg);
// K of a CameraInfo (no distortion assumed). Throws scenario::ConfigError for fx or fy <= 0.
clients::PinholeCamera fromMsg(const sensor_msgs::CameraInfo& msg);

// What perfect perception reports about one entity, as the clients may use it: class and
// attributes (never its id or role).
clients::Observation toObservation(const hameritt::PerceivedEntity& e);

// A detector's blob of `target`'s colour as a perceived entity: its image box (inclusive
// bounds), colour pixels, measured position and long-axis yaw, and the description's class and
// attributes (no entity id or role: the detector does not know them).
hameritt::PerceivedEntity toPerceivedBlob(const scenario::TargetDescription& target,
                                          const clients::CarCandidate& blob);

// A ground-truth entity state (adk/target_state) as the pursuit's vehicle state at mission time
// `t` (the message's stamp less the mission's start): the bottom-centre position, the pose's
// yaw, and the speed along that heading (the horizontal velocity's component, 0 when it points
// backwards).
clients::VehicleState toVehicleState(const hameritt::EntityState& e, double t);

// A claim: "I see `target` at `position`" from the frame stamped `stamp`.
hameritt::Detection makeDetection(const std::string& client,
                                  const scenario::TargetDescription& target,
                                  const geometry::Vec3& position, double confidence,
                                  const ros::Time& stamp);

// The mission of a /mission message, or nullopt (logged as an error for `client`) when it does
// not convert or is for another scenario than `scenario_id` (the client's sim_config).
std::optional<scenario::Mission> acceptMission(const hameritt::Mission& msg,
                                               const std::string& scenario_id, const char* client);

// The mission state in an /adk/state message of any type (see clients::readMissionState).
std::optional<clients::MissionStateReading> readMissionState(const topic_tools::ShapeShifter& msg);

}  // namespace hameritt::ros_wrappers
