#pragma once
// The spec compiler and its constructive sampler: a type-checked spec becomes candidate sets
// computed from the world's indexes (parking places x car models, narrowed requirement by
// requirement with the relation code), and each scenario draws from the feasible set directly.
// No rejection loop: a spec the world cannot satisfy is refused at compile time, naming the
// requirement that emptied the set and the candidates each earlier step left.

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hameritt/generation/generator.h"
#include "hameritt/generation/spec.h"
#include "hameritt/scenario/relations.h"

namespace hameritt::generation {

enum class SamplerKind { kRandom, kHalton };
// "random" or "halton"; false for anything else.
bool parseSampler(const std::string& s, SamplerKind* out);

// One step of the narrowing: what it required and how many candidates were left.
struct NarrowingStep {
  std::string label;
  long long count = 0;
};

// A scenario's draws: the generator configuration with the spec's values fixed, and the plan.
struct ScenarioDraw {
  scenario::GeneratorConfig config;
  scenario::ScenarioPlan plan;
};

struct PlacerChain;

class CompiledSpec {
 public:
  // Throws SpecError (exit 2) when the world cannot satisfy the spec.
  CompiledSpec(Spec spec, const scenario::World& world, const scenario::GeneratorConfig& base);

  // The draws of scenario `index` of a batch (seed: that scenario's seed). Random: from the
  // seed; Halton: point index+1 of the Halton sequence over the spec's continuous settings,
  // scrambled by a shift drawn from `batch_seed` (Cranley-Patterson rotation).
  ScenarioDraw draw(std::uint64_t seed, std::uint64_t index, std::uint64_t batch_seed,
                    SamplerKind sampler) const;

  const Spec& spec() const { return spec_; }
  const std::vector<NarrowingStep>& steps() const { return steps_; }
  // Candidates left with every hard requirement (soft ones not applied).
  std::size_t feasibleCount() const { return hard_.size(); }

 private:
  Spec spec_;
  const scenario::World& world_;
  scenario::GeneratorConfig base_;
  std::vector<int> models_;
  std::vector<std::string> colors_;
  std::vector<std::pair<int, int>> hard_;  // placements meeting every hard requirement
  std::vector<int> soft_;                  // indices of soft requirements in spec_.requirements
  // Per combination of soft outcomes (bit i: soft_[i] holds), the feasible placements.
  std::vector<std::vector<std::pair<int, int>>> combos_;
  std::vector<NarrowingStep> steps_;
  bool placed_ = false;  // the target is parked (area_search, pursuit)
  // route_search with requirements: the lead car's starts (the pairs' first members index it).
  std::vector<scenario::RouteStart> route_starts_;
  // The requirements that place a car or pedestrian beside the target, in the order written.
  std::shared_ptr<const PlacerChain> chain_;
  std::vector<int> placer_soft_;  // per placer: its index in soft_ ('prefer'); -1: hard
  // Per placer, whether it places in a scenario with these soft outcomes (bit i: soft_[i] holds).
  std::vector<char> activePlacers(std::size_t bits) const;
  // The world's relations, for the requirement that tells look-alikes apart.
  std::shared_ptr<const scenario::RelationEvaluator> told_eval_;
};

// Whether some world entity of the requirement's related class and look stands in its relation
// (negation not applied) to a target with this box. `pruned`: the compiler's evaluation, which
// skips other classes and looks before measuring and traces line of sight only where distance
// and bearing leave the relation possible; false: the checker's reference, holds(measure()) on
// every nearby entity. Both give the same answer.
bool worldRelationHolds(const scenario::RelationEvaluator& eval, const scenario::World& world,
                        const Requirement& r, const geometry::OrientedBox& box, bool pruned);

// The facts a hard requirement is checked on, recomputed from the finished scene.
struct RequirementCheck {
  std::string requirement;
  bool holds = false;
  bool soft = false;
};

// Re-checks a finished scenario against the spec from the scene itself: target class, count
// and look, relations recomputed with the relation code, and every drawn value inside its
// distribution's support. Returns one message per violated hard requirement (empty: all hold);
// `soft` receives whether each soft requirement held. `require_listed`: a hard requirement must
// also be listed in the mission's relations and the koz statements' zones be in the mission
// (false: the scene alone counts, as a rejection sampler would judge an unconstrained scene).
std::vector<std::string> checkScenarioAgainstSpec(const Spec& spec, const scenario::World& world,
                                                  const scenario::GeneratorConfig& base,
                                                  const scenario::Mission& mission,
                                                  const scenario::SimConfig& sim,
                                                  std::vector<RequirementCheck>* soft,
                                                  bool require_listed = true);

}  // namespace hameritt::generation
