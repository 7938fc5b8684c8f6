#pragma once
// Reading mission.json: the strict inverse of missionJson() (scenario_io.h), so that planners
// and clients can load the constraints of a scenario written by the generator.
// missionJson(loadMission(f)) is byte-identical to the file f for files the generator wrote.

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "hameritt/scenario/scenario.h"

namespace hameritt::scenario {

// Builds a Mission from a parsed mission document. Unknown keys, missing keys, wrong types and
// out-of-range values are ConfigErrors whose message names `file`, the JSON path
// ("keep_out_zones[1].altitude.min") and what was expected. Relation attributes keep the
// document's key order (hence ordered_json). A relation's "text" must equal relationText() of
// the relation it describes.
Mission missionFromJson(const nlohmann::ordered_json& j, const std::string& file);

// Reads and parses a mission.json file (ConfigError on I/O or syntax errors, with the file).
Mission loadMission(const std::string& path);

// The same from the document's text; `file` names it in messages.
Mission parseMission(const std::string& text, const std::string& file);

}  // namespace hameritt::scenario
