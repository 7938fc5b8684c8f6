#pragma once
// The follow phase's score, kept up sample by sample: the vehicle's states and the target's
// ground truth from the phase's start (the find that ends the search phase) to its duration,
// scored by scoreFollow (navigation_metrics.h). Success: inside the envelope at least
// min_inside_fraction of the phase, never outside longer than max_outside_s, no collision, no
// keep-out violation during the phase, and the whole phase flown. ROS-free.

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
  double duration = 0.0;             // the phase's, from mission.json
  double elapsed = 0.0;              // of the phase, up to the last sample scored
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

  // The search phase succeeded at t: the follow phase begins. Later calls are ignored.
  void start(double t);
  bool started() const { return start_.has_value(); }
  // One sample. Before the start or after the phase's end it is ignored (false). InputError
  // for a stamp that does not increase or a non-finite value, before anything is kept.
  bool add(const FollowSample& sample);
  // The phase's duration has been flown (a sample at or after start + duration).
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
  std::vector<FollowSample> samples_;
  std::optional<double> outside_since_;
  bool exceeded_ = false;
};

}  // namespace hameritt::adk
