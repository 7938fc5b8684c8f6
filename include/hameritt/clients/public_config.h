#pragma once
// The honesty rule of the baseline clients, in code: a client may read the public parts of a
// sim_config.json (the neighborhood's generation parameters and fingerprint: public map data;
// the UAV's own specification: altitude band, speed, payload cameras; the weather, which any
// pilot sees) and nothing else. The scenario's entities (targets, confusers, traffic and their
// trajectories), its groups and the generator's perception-only path are removed from the
// document before it is parsed, so a client never holds them in memory.

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "hameritt/scenario/scenario.h"

namespace hameritt::clients {

// The document with "entities" and "groups" emptied and "uav.perception_path" removed.
nlohmann::ordered_json publicSimConfigJson(const nlohmann::ordered_json& sim_config);

// Reads a sim_config.json as a client may (see above): entities, groups and perception_path
// are empty. Errors are scenario::ConfigErrors naming the file and field, as loadSimConfig's.
scenario::SimConfig loadPublicSimConfig(const std::string& path);

}  // namespace hameritt::clients
