#pragma once
// The symbolic context that tells a target from its look-alikes: confusers share the target's
// class, make, model and colour, and the scenario places them where the mission's context rules
// them out (outside the target's area of interest or its window, outside the route band, or
// without one of the listed scene relations). A ContextFilter checks a candidate's estimated
// pose against that context; both baseline clients use it. ROS-free.
//
// Honest inputs only: the mission, the candidate's estimate (from an image, or from perfect
// perception in maneuver-only mode) and the static neighborhood, which is public map data
// regenerated from the sim_config's world parameters (clients::loadPublicSimConfig).

#include <string>
#include <vector>

#include "hameritt/geometry/oriented_box.h"
#include "hameritt/geometry/types.h"
#include "hameritt/scenario/relations.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::clients {

// Attributes of something seen (perfect perception's key/values, or what a detector measured).
struct Observation {
  std::string entity_class;  // car, pedestrian
  std::vector<std::pair<std::string, std::string>> attributes;
};

// True when every field the description sets (class, vehicle_class, make, model, colour;
// case-insensitive) equals the observation's. An empty field is a wildcard.
bool matchesDescription(const Observation& seen, const scenario::TargetDescription& target);

// "white Toyota RAV4 (suv)".
std::string describe(const scenario::TargetDescription& target);

// The footprint of the car the description names (the catalog's make and model, else typical
// dimensions of its vehicle class, else a mid-size car). Length, width, height in metres.
geometry::Vec3 nominalSize(const scenario::TargetDescription& target);

// A candidate's estimated pose on the ground.
struct CandidatePose {
  geometry::Vec3 position{0, 0, 0};     // bottom-face centre, map frame
  double yaw = 0.0;                     // heading, radians
  bool yaw_ambiguous = true;            // true: the heading may be yaw + pi (an image blob's axis)
  geometry::Vec3 size{4.6, 1.85, 1.6};  // length, width, height
};

// Tolerances of the checks. validate() throws scenario::ConfigError naming "context.<field>".
struct ContextSettings {
  double region_tolerance = 1.5;      // m outside an AOI polygon or band that still counts
  double distance_tolerance = 1.5;    // m between a measured footprint distance and the evidence
  double over_tolerance = 0.75;       // m, ON_TOP_OF / NOT_ON_TOP_OF footprint containment
  double bearing_tolerance_deg = 35;  // directional relations: |bearing - evidence bearing|
  bool check_relations = true;
  // m/s; 0: off. A moving target (pursuit, follow, track) may drive off once its area's window
  // has closed: t seconds past the window's end, a candidate up to drive_off_speed * t (plus
  // region_tolerance) outside the area still counts as in it, its relations unchecked.
  double drive_off_speed = 0.0;
  scenario::RelationConfig thresholds;  // the generator's operator thresholds
  void validate() const;
};

// What the filter concluded.
struct ContextVerdict {
  bool accepted = false;
  std::string region_id;  // the AOI or route the candidate is in ("" when none)
  std::string target_id;  // the mission target whose context it matches ("" when rejected)
  int relations_checked = 0;
  int relations_skipped = 0;  // cannot be checked from a single estimate (see ContextFilter)
  std::string reason;         // why it was rejected, or what was checked
};

// Checks candidates against a mission's context.
//
// Region gate: the candidate must lie in an area of interest whose window is active at the
// observation time, or in a route band (route search). Missions with neither accept anywhere.
//
// Scene relations of the target (when `world` is given and check_relations is set) are checked
// against the related object looked up by id in the static world; each must agree with the
// relation and with its evidence within the tolerances:
// - NEXT_TO, NOT_NEXT_TO: footprint distance within distance_tolerance of the evidence distance
//   (and below next_to_distance + tolerance for NEXT_TO);
// - ON_TOP_OF: candidate centre over the related footprint (within over_tolerance);
//   NOT_ON_TOP_OF: centre not inside the related footprint by more than over_tolerance;
// - LEFT_OF, RIGHT_OF, IN_FRONT_OF, ORTHOGONAL_TO: footprint distance as NEXT_TO's, bearing of the
//   related centre in the candidate's body frame within bearing_tolerance_deg of the evidence
//   (either heading when the heading is ambiguous; ORTHOGONAL_TO also its mirror);
// - PART_OF a block group: the candidate stands in that block.
// Skipped (counted in relations_skipped): EVENTUALLY_* relations (they hold at a later time),
// related objects that are not in the static world (scenario cars, pedestrians, convoy and
// vignette groups), line of sight and dz (need the true box), and every relation when the
// target moves (route search; pursuit once its AOI window has closed): relations describe t = 0.
// With drive_off_speed, a moving target's candidate within reach of its AOI past the window's end
// passes the region gate (region_id the AOI's, its relations skipped).
// A mission with several targets of this description accepts the candidate when one target's
// context holds.
class ContextFilter {
 public:
  // `world` may be null (no relation checks). Both must outlive the filter.
  ContextFilter(const scenario::Mission& mission, const scenario::World* world,
                const ContextSettings& settings = {});

  // Checks a candidate seen at mission time t that matches `target`'s description.
  ContextVerdict check(const CandidatePose& candidate, double t,
                       const scenario::TargetDescription& target) const;

  // The mission targets whose description the observation matches.
  std::vector<const scenario::TargetDescription*> targetsMatching(const Observation& seen) const;

  const scenario::Mission& mission() const { return mission_; }

 private:
  // "" when the relation holds (or is skipped: *skipped = true), else why it does not.
  std::string checkRelation(const scenario::SceneRelation& rel, const CandidatePose& c,
                            bool* skipped) const;
  // The AOI or route the point is in at t ("" when none); *driven_off: in an AOI's reach past
  // its window only (drive_off_speed).
  std::string regionOf(const geometry::Vec2& p, double t, bool* driven_off) const;

  const scenario::Mission& mission_;
  const scenario::World* world_;
  ContextSettings settings_;
};

}  // namespace hameritt::clients
