// hameritt_check_path's path reader: parsePathCsv() accepts or throws ConfigError; an accepted
// path written with pathCsv() reads back to the same samples, bit for bit.
#include "fuzz_util.h"
#include "hameritt/adk/path_csv.h"
#include "hameritt/scenario/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hameritt;
  try {
    const auto path = adk::parsePathCsv(fuzz::text(data, size), "fuzz.csv");
    fuzz::require(!path.empty(), "an accepted path has samples");
    const auto again = adk::parsePathCsv(adk::pathCsv(path), "written.csv");
    fuzz::require(again.size() == path.size(), "pathCsv round trip keeps the sample count");
    for (std::size_t i = 0; i < path.size(); ++i) {
      fuzz::require(again[i].t == path[i].t && again[i].p == path[i].p,
                    "pathCsv round trip keeps every number");
      fuzz::require(i == 0 || path[i].t > path[i - 1].t, "times strictly increase");
    }
  } catch (const scenario::ConfigError&) {
  }
  return 0;
}
