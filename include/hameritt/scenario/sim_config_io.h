#pragma once
// Reading sim_config.json: the strict inverse of simConfigJson() (scenario_io.h), so that the
// simulator can load a scenario written by the generator. simConfigJson(loadSimConfig(f)) is
// byte-identical to the file f for files the generator wrote.

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

// Builds a SimConfig from a parsed sim_config document. Unknown keys, missing keys, wrong types
// and out-of-range values are ConfigErrors whose message names `file`, the JSON path
// ("entities[3].trajectory[2]") and what was expected. Entity attributes keep the document's
// key order, so parse with nlohmann::ordered_json for a byte-exact round trip (nlohmann::json
// sorts keys; its overload gives attributes in sorted order).
SimConfig simConfigFromJson(const nlohmann::ordered_json& j, const std::string& file);
SimConfig simConfigFromJson(const nlohmann::json& j, const std::string& file);

// Reads and parses a sim_config.json file (ConfigError on I/O or syntax errors, with the file),
// keeping key order.
SimConfig loadSimConfig(const std::string& path);

// The same from the document's text; `file` names it in messages.
SimConfig parseSimConfig(const std::string& text, const std::string& file);

// Regenerates the neighborhood from the sim_config's world parameters and checks it against the
// recorded fingerprint (ConfigError naming `file` and world.fingerprint on a mismatch).
World generateCheckedWorld(const SimConfig& config, const std::string& file);

}  // namespace hameritt::scenario
