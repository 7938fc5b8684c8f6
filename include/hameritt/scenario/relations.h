#pragma once
// Scene relations computed from geometry, as the HAMERITT paper defines its operators:
// [related] [OPERATOR] [target]. Distances are between 2D footprints; bearings are of the
// related entity's centre in the target's body frame (x along the target's yaw), counter-
// clockwise positive, in [0, 360): LEFT_OF ~ 90, IN_FRONT_OF ~ 180, RIGHT_OF ~ 270,
// ORTHOGONAL_TO ~ 90 or 270. Line of sight runs between the two box centres and is blocked by
// any other occluder (see occluderBoxes()).

#include <optional>
#include <string>
#include <vector>

#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

// Thresholds of the relation operators (config/generator.json "relations").
struct RelationConfig {
  double next_to_distance = 3.0;       // NEXT_TO: footprint distance below this, with sight
  double radius = 15.0;                // other spatial operators: related entity within this
  double bearing_tolerance_deg = 20.0;  // directional operators: |bearing - nominal| <= this
  double on_top_tolerance = 0.03;      // ON_TOP_OF: |target min z - related max z| <= this
  int max_relations = 6;               // relations listed per target in the mission
  double eventually_dt = 0.5;          // trajectory sampling step for EVENTUALLY_*

  void validate() const;
};

// Something that relations are evaluated on: a world entity, or a scenario entity posed at
// some time.
struct Subject {
  std::string id;
  EntityClass cls = EntityClass::kCar;
  const Attributes* attributes = nullptr;
  geometry::OrientedBox box;
  int world_index = -1;  // index in World::entities(), or -1
};

// Measurements between a target and a related subject.
struct RelationFacts {
  double distance = 0.0;
  double bearing_deg = 0.0;
  double dz = 0.0;
  bool line_of_sight = false;
  bool over = false;  // target centre inside the related footprint
};

// Evaluates relations against the static world plus a few scenario boxes that also occlude
// (parked scenario cars). Thread-safe for concurrent const use.
class RelationEvaluator {
 public:
  RelationEvaluator(const World& world, const RelationConfig& config);

  // Adds a static scenario occluder (e.g. a parked target or confuser) with its id.
  void addOccluder(const std::string& id, const geometry::OrientedBox& box);
  // Removes the scenario occluder with this id, if any.
  void removeOccluder(const std::string& id);

  RelationFacts measure(const Subject& target, const Subject& related) const;
  // measure() for NEXT_TO, LEFT_OF and RIGHT_OF only: `over` is left false, and line of sight
  // is only computed where one of them could hold (else false), so holds() gives the same
  // answer for those three operators.
  // `distance`: footprintDistance(target.box, related.box), when the caller has it.
  RelationFacts measureSideways(const Subject& target, const Subject& related,
                                std::optional<double> distance = std::nullopt) const;
  // True when `op` (not PART_OF) holds for these facts and the related class.
  bool holds(RelationOp op, const RelationFacts& f, EntityClass related_cls) const;
  // Line of sight between two box centres, ignoring the two subjects themselves.
  bool lineOfSight(const Subject& a, const Subject& b) const;

  // World entities whose footprint lies within the relation radius of the target's footprint.
  std::vector<int> nearbyWorld(const geometry::OrientedBox& target) const;
  // nearbyWorld() with each entity's footprint distance to the target alongside.
  std::vector<std::pair<int, double>> nearbyWorldDistances(
      const geometry::OrientedBox& target) const;

  // Every true relation of the target at this instant against nearby world entities and the
  // given extra subjects (pedestrians, other scenario cars), and PART_OF its groups.
  std::vector<SceneRelation> allRelations(const Subject& target,
                                          const std::vector<Subject>& extra,
                                          const std::vector<const Group*>& groups) const;

  // True when some entity of the relation's related class and attributes satisfies the
  // relation with `candidate` (world entities, plus `extra`). For PART_OF, group membership.
  bool satisfiedBy(const SceneRelation& rel, const Subject& candidate,
                   const std::vector<Subject>& extra,
                   const std::vector<Group>& groups) const;

  const RelationConfig& config() const { return config_; }
  const World& world() const { return world_; }

 private:
  const World& world_;
  RelationConfig config_;
  // An occluder added by addOccluder(): its box's yaw cosine and sine, and bounds that hold the
  // box with a centimetre to spare (a sight line that misses them misses the box).
  struct ExtraOccluder {
    std::string id;
    geometry::OrientedBox box;
    double cos_yaw = 1.0, sin_yaw = 0.0;
    geometry::Vec3 lo, hi;
  };
  std::vector<ExtraOccluder> extra_occluders_;
};

// The classes that each operator considers as related entities.
bool operatorApplies(RelationOp op, EntityClass related_cls);

// The relation `op` between two subjects with its evidence (not EVENTUALLY, no time).
SceneRelation makeRelation(const Subject& target, const Subject& related, RelationOp op,
                           const RelationFacts& facts);

// A subject for world entity i.
Subject worldSubject(const World& world, int i);

}  // namespace hameritt::scenario
