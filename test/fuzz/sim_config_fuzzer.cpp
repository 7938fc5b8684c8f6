// sim_config.json reader (the simulator's and the renderer's configuration: world parameters,
// entities, trajectories, cameras, environment): parseSimConfig() accepts or throws
// ConfigError; an accepted config written back with simConfigJson() reads back to the same text.
#include "fuzz_util.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/sim_config_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hameritt;
  try {
    const scenario::SimConfig c = scenario::parseSimConfig(fuzz::text(data, size), "fuzz.json");
    const std::string once = scenario::simConfigJson(c);
    const std::string twice =
        scenario::simConfigJson(scenario::parseSimConfig(once, "written.json"));
    fuzz::require(once == twice, "simConfigJson(parseSimConfig(simConfigJson(c))) == simConfigJson(c)");
  } catch (const scenario::ConfigError&) {
  }
  return 0;
}
