#pragma once
// Private to the scenario library: the signal plan as written in sim_config.json ("signals") and
// in a traffic episode file, and its strict reader.

#include <string>

#include "hameritt/scenario/json_writer.h"
#include "hameritt/scenario/scenario.h"
#include "strict_json.h"

namespace hameritt::scenario {

// The plan's object (the caller has written its key).
void writeSignalPlan(JsonWriter& w, const SignalPlan& sp);

// Reads the plan object `sg` (at JSON path `path`) and finishes it.
SignalPlan readSignalPlan(strict_json::Object& sg, const std::string& path,
                          const std::string& file);

}  // namespace hameritt::scenario
