#pragma once
// Shared fixtures of the scenario tests: the shipped configuration and its world, built once.

#include <unistd.h>

#include <filesystem>
#include <functional>
#include <fstream>
#include <sstream>
#include <string>

#include "hameritt/scenario/error.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario::testing {

inline const GeneratorConfig& shippedConfig() {
  static const GeneratorConfig c = loadGeneratorConfig(defaultConfigDir() + "/generator.json");
  return c;
}

inline const World& shippedWorld() {
  static const World w = generateWorld(loadWorldParams(defaultConfigDir() + "/world.json"));
  return w;
}

// The shipped world parameters with the city type.
inline const World& shippedCityWorld() {
  static const World w = [] {
    WorldParams p = loadWorldParams(defaultConfigDir() + "/world.json");
    p.type = WorldType::kCity;
    return generateWorld(p);
  }();
  return w;
}

// What f throws as a ConfigError, or "(no error)".
inline std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

// The whole file as bytes ("" if it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// A fresh, empty temporary directory unique to this process and tag.
inline std::string freshTempDir(const std::string& tag) {
  const std::string d = std::filesystem::temp_directory_path().string() + "/hameritt_test_" + tag +
                        "_" + std::to_string(::getpid());
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

}  // namespace hameritt::scenario::testing
