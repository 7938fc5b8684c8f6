// config/world.json reader (world parameters): parseJsonString() + worldParamsFromJson() accept
// or throw ConfigError; accepted parameters of a small neighbourhood generate a world.
#include <nlohmann/json.hpp>

#include "fuzz_util.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/params_table.h"
#include "hameritt/scenario/world.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hameritt;
  try {
    const nlohmann::json j = scenario::parseJsonString(fuzz::text(data, size), "fuzz.json");
    const scenario::WorldParams p = scenario::worldParamsFromJson(j, "fuzz.json");
    // Generation costs ~ the area: only small worlds, so that each run stays fast.
    if (p.extent_x * p.extent_y <= 600.0 * 600.0) {
      const scenario::World w = scenario::generateWorld(p);
      fuzz::require(!w.blocks().empty() || w.entities().empty(), "a world with entities has blocks");
    }
  } catch (const scenario::ConfigError&) {
  }
  return 0;
}
