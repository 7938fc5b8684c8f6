#pragma once
// The follow phase's score, kept up sample by sample. The phase starts at the find that ends
// the search phase; the vehicle then approaches the envelope, and the scored part of the phase
// (its `duration`) starts at the first sample inside the envelope, or at the first sample
// approach_s after the find if none was inside by then. From there the vehicle's states and
// the target's ground truth are scored by scoreFollow (navigation_metrics.h). Success: inside
// the envelope at least min_inside_fraction of the scored part, never outside longer than
// max_outside_s in it, no collision and no keep-out violation from the find on, and the whole
// duration flown. ROS-free.

#include <optional>
#include <string>
#include <vector>

#include "hameritt/adk/navigation_metrics.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::adk {

// Where a phase stands: pending (not begun), active, succeeded, failed.
enum class PhaseState { kPending, kActive, kSucceeded, kFailed };
// "pending", "active", "succeeded", "failed".
const char* toString(PhaseState s);

struct FollowPhaseScore {
  std::string phase;   // the phase's id
  std::string target;  // the followed target's id
  PhaseState state = PhaseState::kPending;
  std::optional<double> start_time;  // the find
  double approach_time = 0.0;        // from the find to the scored part's start (or so far)
  double duration = 0.0;             // the scored part's, from mission.json
  double elapsed = 0.0;              // of the scored part, up to the last sample scored
  bool outside = false;              // the last sample lay outside the envelope
  double current_outside_s = 0.0;    // how long it has been outside (0 when inside)
  FollowScore envelope;              // inside fraction, errors, line of sight, longest outside
  double koz_seconds = 0.0;          // keep-out violation seconds during the phase
  bool collision = false;
  bool success = false;
  std::string failure;  // why not, "" on success (and while the phase is pending or active)
};

class FollowScorer {
 public:
  // `phase` must be a follow phase with one target and a duration. Throws scenario::ConfigError
  // naming "follow.<field>" for a bad envelope, criteria or duration.
  explicit FollowScorer(const scenario::MissionPhase& phase);

  // The search phase succeeded at t: the follow phase begins with its approach. Later calls
  // are ignored.
  void start(double t);
  bool started() const { return start_.has_value(); }
  // The approach is over: the scored part has begun (at this time).
  std::optional<double> scoredFrom() const { return scored_from_; }
  // One sample. Before the start or after the phase's end it is ignored (false). InputError
  // for a stamp that does not increase or a non-finite value, before anything is kept.
  bool add(const FollowSample& sample);
  // The phase's duration has been flown (a sample at or after the scored start + duration).
  bool complete() const;
  // The phase can no longer succeed: it has been outside the envelope for longer than
  // max_outside_s at a stretch (it stays so once it has happened).
  bool failedEarly() const;

  // The score so far; `koz_seconds` and `collision` over the phase, from the constraint monitor
  // and the simulator. `ended`: the mission is over, so a phase not complete has failed.
  FollowPhaseScore score(double koz_seconds, bool collision, bool ended) const;

  const scenario::MissionPhase& phase() const { return phase_; }
  const FollowEnvelope& envelope() const { return envelope_; }

 private:
  scenario::MissionPhase phase_;
  FollowEnvelope envelope_;
  FollowCriteria criteria_;
  std::optional<double> start_;
  std::optional<double> scored_from_;
  // Of any sample kept or used for the approach: once scoring has begun, the last scored one.
  std::optional<double> last_t_;
  FollowAccumulator accumulator_;  // the scored samples' envelope figures, kept as they come
  std::optional<double> outside_since_;
  bool exceeded_ = false;
};

}  // namespace hameritt::adk
