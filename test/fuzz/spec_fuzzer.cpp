// Scenario language (.hspec): parseSpecText() and the compiler accept a spec or throw
// ConfigError (SpecError for syntax, type, name and unsatisfiable specs), never crash or hang; an
// accepted spec draws scenarios whose values lie inside their distributions, with both samplers.
// A first line "#params A=B C=D" passes --param overrides. The world is a small neighbourhood.
#include <sstream>

#include "fuzz_util.h"
#include "hameritt/generation/spec.h"
#include "hameritt/generation/spec_sampler.h"
#include "hameritt/scenario/error.h"

namespace {

const hameritt::scenario::World& smallWorld() {
  static const hameritt::scenario::World w = [] {
    hameritt::scenario::WorldParams p;
    p.extent_x = 450.0;
    p.extent_y = 400.0;
    return hameritt::scenario::generateWorld(p);
  }();
  return w;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hameritt;
  const std::string text = fuzz::text(data, size);
  std::vector<std::string> params;
  if (text.rfind("#params ", 0) == 0) {
    std::istringstream line(text.substr(8, text.find('\n') - 8));
    for (std::string p; line >> p;) params.push_back(p);
  }
  try {
    const generation::Spec spec =
        generation::parseSpecText(text, "fuzz.hspec", params, smallWorld());
    scenario::GeneratorConfig cfg;
    const generation::CompiledSpec compiled(spec, smallWorld(), cfg);
    for (auto sampler : {generation::SamplerKind::kRandom, generation::SamplerKind::kHalton}) {
      for (std::uint64_t i = 0; i < 3; ++i) {
        const generation::ScenarioDraw d = compiled.draw(i + 1, i, 7, sampler);
        fuzz::require(d.plan.provenance.has_value(), "a draw carries its provenance");
        std::size_t k = 0;
        for (const auto& [key, dist] : spec.settings) {
          const auto& v = d.plan.provenance->values[k++];
          fuzz::require(v.first == key, "provenance lists the settings in order");
          fuzz::require(dist.contains(std::get<double>(v.second)),
                        "a drawn value is inside its distribution");
        }
        if (d.plan.placements) {
          fuzz::require(!d.plan.placements->empty(),
                        "a compiled spec never draws from an empty set");
        }
      }
    }
  } catch (const scenario::ConfigError&) {
  }
  return 0;
}
