#pragma once
// The mission description between the scenario core and ROS: scenario::Mission (mission.json)
// <-> hameritt/Mission (published latched on /mission by the ADK). fromMsg(toMsg(m)) == m for
// every field the message carries (all but the frame's type and units, always ENU metres).

#include <string>
#include <vector>

#include "hameritt/KeyValue.h"
#include "hameritt/Mission.h"
#include "hameritt/UavSpec.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::ros_wrappers {

hameritt::Mission toMsg(const scenario::Mission& mission);

// Attributes as key/value strings (integers in decimal; fromMsg reads them back as integers).
std::vector<hameritt::KeyValue> toKeyValues(const scenario::Attributes& a);

// Throws scenario::ConfigError naming the field for an unknown scenario class or relation
// operator, or a polygon with fewer than 3 points.
scenario::Mission fromMsg(const hameritt::Mission& msg);

// The UAV's envelope (sim_config.json "uav": flight band, speed, start pose, payload cameras)
// <-> hameritt/UavSpec (published latched on /mission/uav by the ADK). The generator's
// perception path is ground truth and is never carried. fromMsg(toMsg(u)) equals u in every
// other field.
hameritt::UavSpec toMsg(const scenario::UavSpec& uav, const std::string& scenario_id);
// Throws scenario::ConfigError naming the field for a band that is not min < max, a speed or
// camera size, field of view or rate that is not positive, or a non-finite number.
scenario::UavSpec fromMsg(const hameritt::UavSpec& msg);

}  // namespace hameritt::ros_wrappers
