#pragma once
// Scoring a perception client's detections against ground truth: which entity a claim refers
// to (the nearest entity of the claimed class within a gate), and whether that is a mission
// target, a confuser (same make, model and colour, placed where the symbolic context tells it
// apart) or something else. ROS-free; the ADK node feeds it the ground truth at each
// detection's stamp.

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "hameritt/adk/intervals.h"
#include "hameritt/geometry/types.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::adk {

// Ground truth of one entity of interest at some time: bottom-face centre (map, ENU) and yaw.
struct EntityTruth {
  std::string id;
  std::string cls;   // "car", "pedestrian"
  std::string role;  // target, confuser, traffic, pedestrian, vignette, or world
  geometry::Vec3 position{0, 0, 0};
  double yaw = 0.0;
};

// Ground-truth snapshots of the scenario's movers over a recent horizon (the simulator's
// /ground_truth/entities), so that a detection or an image stamped a little in the past is
// judged against where things were then.
class GroundTruthHistory {
 public:
  // Keeps snapshots no older than `horizon` seconds before the newest (> 0).
  explicit GroundTruthHistory(double horizon = 10.0);

  // Adds a snapshot at time t. A time not after the newest one is a restart of the clock (a
  // simulator reset): the history is cleared first. Non-finite t: InputError.
  void add(double t, std::vector<EntityTruth> entities);
  bool empty() const { return snapshots_.empty(); }
  double newestTime() const;

  // Every entity at time t: linear interpolation in position (yaw along the shorter arc)
  // between the two snapshots around t; before the oldest or after the newest snapshot, that
  // snapshot as it is. An entity missing from one of the two snapshots comes from the other.
  // Empty when there is no snapshot.
  std::vector<EntityTruth> at(double t) const;

 private:
  struct Snapshot {
    double t;
    std::vector<EntityTruth> entities;
  };
  double horizon_;
  std::vector<Snapshot> snapshots_;
};

// A scenario entity (from sim_config) at time t, from its trajectory as the simulator moves it
// (pose of a parked entity), with its role.
EntityTruth scenarioEntityAt(const scenario::ScenarioEntity& e, double t);

// Matching gates (horizontal distance between the claimed and the true bottom-face centre).
// A car is about 4.5 m long: a claim anywhere on it, with a few metres of localisation error,
// matches; a pedestrian is small and often near others, hence the tighter gate.
struct ScoringSettings {
  double car_gate = 6.0;         // m
  double pedestrian_gate = 3.0;  // m
  // Throws scenario::ConfigError naming "scoring.<field>" and the bad value.
  void validate() const;
};

// A perception client's claim (hameritt/Detection).
struct DetectionClaim {
  double stamp = 0.0;        // sim time of the image it comes from
  std::string entity_class;  // "car", "pedestrian", or "" for either
  geometry::Vec3 position{0, 0, 0};
  double confidence = 1.0;
};

enum class Verdict { kTarget, kConfuser, kOther, kNone };
// "target", "confuser", "other", "none".
const char* toString(Verdict v);

struct DetectionVerdict {
  Verdict verdict = Verdict::kNone;
  std::string entity_id;        // "" for none
  std::string role;             // the matched entity's role ("" for none)
  double position_error = 0.0;  // horizontal, metres (0 for none)
  bool first_correct = false;   // the first correct detection of that target
};

// Matches claims to entities. Target: a mission objective's target; confuser: role confuser;
// other: any other car or pedestrian (traffic, pedestrians, vignette, parked world cars);
// none: no entity of the claimed class within its gate. Claim attributes are not used: a claim
// names a position, and the verdict says what is there.
class DetectionScorer {
 public:
  // Throws scenario::ConfigError when an objective target is not among `entities`.
  DetectionScorer(const scenario::Mission& mission,
                  const std::vector<scenario::ScenarioEntity>& entities,
                  const ScoringSettings& settings = {});

  // Scores a claim against the entities' ground truth at the claim's stamp (scenario entities
  // and parked world cars). Throws InputError for a non-finite position or stamp.
  DetectionVerdict score(const DetectionClaim& claim, const std::vector<EntityTruth>& truth);

  const ScoringSettings& settings() const { return settings_; }
  // Objective target ids, in the mission's order.
  const std::vector<std::string>& targets() const { return targets_; }

 private:
  ScoringSettings settings_;
  std::vector<std::string> targets_;
  std::map<std::string, std::string> roles_;  // scenario entity id -> role
  std::map<std::string, bool> found_;         // target id -> a correct detection was scored
};

}  // namespace hameritt::adk
