// mission.json reader: parseMission() accepts or throws ConfigError; an accepted mission
// written back with missionJson() reads back to the same text (writer and reader agree).
#include "fuzz_util.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/scenario_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hameritt;
  try {
    const scenario::Mission m = scenario::parseMission(fuzz::text(data, size), "fuzz.json");
    const std::string once = scenario::missionJson(m);
    const std::string twice = scenario::missionJson(scenario::parseMission(once, "written.json"));
    fuzz::require(once == twice, "missionJson(parseMission(missionJson(m))) == missionJson(m)");
  } catch (const scenario::ConfigError&) {
  }
  return 0;
}
