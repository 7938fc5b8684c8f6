#pragma once
// Random scenario generation: a seed and a class in, a complete, self-consistent scenario out.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "hameritt/generation/target_slots.h"
#include "hameritt/scenario/generator_config.h"
#include "hameritt/scenario/rng.h"

namespace hameritt::scenario {

// "<class>-<16 hex digits of the seed>", e.g. "area_search-00000000000004d2".
std::string scenarioId(ScenarioClass cls, std::uint64_t seed);

// A car or pedestrian to put beside the target so that a spec's relation to it holds: its pose,
// look and (cars) the parking place it takes.
struct RelatedOption {
  EntityClass cls = EntityClass::kCar;
  geometry::OrientedBox box;
  int slot = -1;  // parking slot of a car, -1 for a standing pedestrian
  Attributes attributes;
};

// What a spec fixes for one scenario beyond the generator's ranges (generation/spec_sampler.h
// fills it): the target's feasible placements and looks, the relations the mission must list,
// and environment values. Null members leave the random generator's choice.
struct ScenarioPlan {
  // Feasible (parking slot, catalog model index) pairs of a parked target; drawn from directly.
  const std::vector<std::pair<int, int>>* placements = nullptr;
  std::vector<int> models;          // allowed catalog models (moving targets); empty: any
  std::vector<std::string> colors;  // allowed colours; empty: any
  int target_count = 0;             // route_search: 1 or 2 cars; 0: the generator decides
  // Each predicate names a relation that the mission's description must list (the hard
  // requirements), picked among the true relations of the target.
  std::vector<std::function<bool(const SceneRelation&)>> listed;
  std::optional<double> koz_window_probability;
  std::optional<double> snow, rain, dust, fog;
  // area_search: the target's distance from the centre of the AOI that holds it (m).
  std::optional<double> aoi_target_offset;
  // The UAV starts at an intersection at most this far from the first target (m) and at least
  // min(120, this / 2) from it.
  std::optional<double> uav_start_within;
  std::optional<SpecProvenance> provenance;
  // Given the parked target's box: the cars and pedestrians that a spec's relations place
  // beside it, drawn with the generator's `rng` (the generator adds each as a parked traffic car
  // or a standing pedestrian, in order); none for a relation the scene already meets. Null: none.
  std::function<std::vector<RelatedOption>(const geometry::OrientedBox&, Rng&)> related;
  // Look-alikes: the attributes they share with the target (vehicle_class, make, model,
  // color; the others differ); unset: make, model and colour.
  std::optional<std::vector<std::string>> confuser_share;
  // Look-alikes park at most this far from the target (m), drawn among every such place.
  std::optional<double> confuser_within;
  // True when a look-alike parked with this box fails the requirement that tells it apart.
  std::function<bool(const geometry::OrientedBox&)> confuser_told_apart;
  // route_search: the lead target's feasible starts; `placements` then holds (index here,
  // catalog model) pairs, tried in a seeded order until one has a route.
  const std::vector<RouteStart>* route_starts = nullptr;
  // An EVENTUALLY_* requirement on a moving target against the world's entities: the mission
  // lists the first trajectory sample at which a matching entity, not so related at t = 0,
  // stands in the relation.
  struct Eventual {
    RelationOp op = RelationOp::kNextTo;
    std::function<bool(EntityClass, const Attributes&)> matches;
  };
  std::vector<Eventual> eventually;
  // A spec's keep-out zones (koz statements) with their drawn numbers: over the first target's
  // position at t = 0 (a square of `size` m along its heading), the block it is on or nearest
  // to (its land grown by `margin` m), its street (a band of the street's width + 2 `margin`,
  // `length` m along it, centred where the target is), the `aoi`-th AOI (grown by `margin` m),
  // or the `count` world entities of class `over` nearest it (footprints grown by `margin` m).
  // Added after the class's own zones.
  struct Koz {
    std::string purpose;
    std::string over;  // "target", "block", "street", "aoi" or an entity class
    int count = 1;
    int aoi = 0;  // over "aoi": 1-based
    double size = 40.0;
    double margin = 5.0;
    double length = 60.0;
    std::optional<double> alt_min, alt_max, net, nlt;
  };
  std::vector<Koz> kozs;
};

// The polygon of a spec keep-out zone over a target with this box at t = 0 (`over` "target"),
// its block, its street, the mission's AOI `aoi` (from `aois`; none when it has fewer), or over
// each of the `count` world entities of class `over` nearest it (centre distance, ties by
// index): what the generator writes and hameritt_validate --spec expects.
std::vector<geometry::Polygon> specKozPolygons(const World& world, const ScenarioPlan::Koz& koz,
                                               const geometry::OrientedBox& target,
                                               const std::vector<AreaOfInterest>& aois = {});

// Generates one scenario. Deterministic: the same world, config, class and seed (and plan) give
// the same scenario. Throws GenerationError when no placement satisfies the constraints.
// traffic_by_reference: the caller writes a city scenario's shared traffic episode as a
// reference (simConfigJson(..., true)), so the episode's cars and walking pedestrians are not
// built in memory, only named by the reference (TrafficEpisodeRef::lean); everything written is
// the same, and the scenario cannot be written inline.
Scenario generateScenario(const World& world, const GeneratorConfig& config, ScenarioClass cls,
                          std::uint64_t seed, const ScenarioPlan* plan = nullptr,
                          bool traffic_by_reference = false);

// The traffic episode (scenario/city_traffic.h) that a city scenario of seed `seed` draws when
// it lasts at most half an episode (a longer one simulates its own cars): a batch simulates the
// episodes its scenarios draw first, side by side.
int cityScenarioEpisode(const World& world, std::uint64_t seed);

// Seed of the i-th scenario of a batch with base seed `seed`.
std::uint64_t batchSeed(std::uint64_t seed, std::uint64_t index);

}  // namespace hameritt::scenario
