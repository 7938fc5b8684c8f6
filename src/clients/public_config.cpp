#include "hameritt/clients/public_config.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hameritt/scenario/bounded_json.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/sim_config_io.h"

namespace hameritt::clients {

nlohmann::ordered_json publicSimConfigJson(const nlohmann::ordered_json& sim_config) {
  nlohmann::ordered_json j = sim_config;
  if (j.is_object()) {
    if (j.contains("entities")) j["entities"] = nlohmann::ordered_json::array();
    if (j.contains("groups")) j["groups"] = nlohmann::ordered_json::array();
    j.erase("traffic");  // the ambient cars of a shared traffic episode are entities too
    if (j.contains("uav") && j["uav"].is_object()) j["uav"].erase("perception_path");
  }
  return j;
}

scenario::SimConfig loadPublicSimConfig(const std::string& path) {
  const std::string text = scenario::readBoundedJsonFile(path);
  nlohmann::ordered_json j;
  try {
    j = nlohmann::ordered_json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw scenario::ConfigError(path + ": not valid JSON: " + e.what());
  }
  return scenario::simConfigFromJson(publicSimConfigJson(j), path);
}

}  // namespace hameritt::clients
