// The renderer's models/meshes/lod.json reader: parseLodManifest() accepts or throws
// RenderError; accepted levels keep to their documented ranges.
#include <cmath>

#include "fuzz_util.h"
#include "hameritt/render/renderer.h"
#include "lod_manifest.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hameritt;
  static const std::set<std::string> meshes = {"house_1", "house_2", "garage_1", "car_sedan",
                                               "tree_pine", "pedestrian"};
  try {
    for (const auto& e : render::parseLodManifest(fuzz::text(data, size), "lod.json", "meshes/",
                                                  meshes)) {
      fuzz::require(meshes.count(e.mesh) == 1, "a known class mesh");
      fuzz::require(!e.levels.empty() && e.levels.size() <= render::kMaxLodLevels, "1 to 4 levels");
      fuzz::require((e.design_size_m.array() > 0).all() && e.design_size_m.allFinite(),
                    "design size > 0");
      double previous = -1;
      for (const auto& l : e.levels) {
        fuzz::require(std::isfinite(l.max_deviation_m) && l.max_deviation_m > previous,
                      "increasing finite deviations");
        previous = l.max_deviation_m;
      }
    }
  } catch (const render::RenderError&) {
  }
  return 0;
}
