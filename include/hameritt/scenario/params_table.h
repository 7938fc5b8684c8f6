#pragma once
// Field tables for the configuration structs: one list of (JSON key, member) per struct serves
// the writer and the strict loader, so the two cannot drift apart.

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "hameritt/scenario/generator_config.h"
#include "hameritt/scenario/json_writer.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

// Writes the world parameters as a JSON object.
void writeWorldParams(JsonWriter& w, const WorldParams& p);
// Reads world parameters from a JSON object; `file` prefixes error messages, followed by the
// JSON path ("world.<key>"). Unknown keys, missing keys and wrong types are ConfigErrors; then
// validate() runs.
WorldParams worldParamsFromJson(const nlohmann::json& j, const std::string& file);
GeneratorConfig generatorConfigFromJson(const nlohmann::json& j, const std::string& file);
void writeGeneratorConfig(JsonWriter& w, const GeneratorConfig& c);
// Parses a JSON file; a syntax error is a ConfigError with the file, line and column.
nlohmann::json readJsonFile(const std::string& path);
// Parses a JSON text; a syntax error is a ConfigError naming `file`, the line and column.
nlohmann::json parseJsonString(const std::string& text, const std::string& file);

}  // namespace hameritt::scenario
