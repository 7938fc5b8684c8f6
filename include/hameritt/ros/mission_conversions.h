#pragma once
// The mission description between the scenario core and ROS: scenario::Mission (mission.json)
// <-> hameritt/Mission (published latched on /mission by the ADK). fromMsg(toMsg(m)) == m for
// every field the message carries (all but the frame's type and units, always ENU metres).

#include <vector>

#include "hameritt/KeyValue.h"
#include "hameritt/Mission.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::ros_wrappers {

hameritt::Mission toMsg(const scenario::Mission& mission);

// Attributes as key/value strings (integers in decimal; fromMsg reads them back as integers).
std::vector<hameritt::KeyValue> toKeyValues(const scenario::Attributes& a);

// Throws scenario::ConfigError naming the field for an unknown scenario class or relation
// operator, or a polygon with fewer than 3 points.
scenario::Mission fromMsg(const hameritt::Mission& msg);

}  // namespace hameritt::ros_wrappers
