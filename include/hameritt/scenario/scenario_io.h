#pragma once
// Scenario files: mission.json, sim_config.json, world.json and manifest.json writers, and
// atomic file and directory output.

#include <string>

#include "hameritt/scenario/generator_config.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

std::string missionJson(const Mission& m);
// traffic_by_reference: as a batch writes it (SimConfig::traffic; see writeScenarioDir()).
std::string simConfigJson(const SimConfig& s, bool traffic_by_reference = false);
// The whole neighborhood: street graph, blocks, parking slots and every entity.
std::string worldJson(const World& w);
// World parameters as the "params" object used in config/world.json and sim_config.json.
std::string worldParamsJson(const WorldParams& p);
// "[garage] [RIGHT_OF] [car_12] [color: white, doors: 1]"
std::string relationText(const SceneRelation& r);
// 16 lower-case hex digits.
std::string hex64(std::uint64_t v);

// Writes `content` to `path` through a temporary file in the same directory and a rename, so
// that readers never see a partial file. Throws OutputError naming the path.
void writeFileAtomic(const std::string& path, const std::string& content);

// Moves the finished directory `tmp` to `final_path` (same file system): a rename or, where
// `final_path` exists, an atomic exchange (renameat2 RENAME_EXCHANGE) and the removal of the
// old one, so that `final_path` names a complete directory at every instant. Throws OutputError.
void replaceDirectory(const std::string& tmp, const std::string& final_path);

// Writes DIR/<scenario_id>/{mission.json, sim_config.json} through a temporary directory that
// is renamed into place (replacing an older scenario of the same id). Returns the directory.
// traffic_by_reference: a city scenario's episode cars are written as a reference to the shared
// traffic episode file (SimConfig::traffic) instead of inline; the caller writes that file.
std::string writeScenarioDir(const std::string& dir, const Scenario& s,
                             bool traffic_by_reference = false);

}  // namespace hameritt::scenario
